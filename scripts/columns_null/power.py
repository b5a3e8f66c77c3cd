"""Detection of noise columns of the wrong shape on a `plinth simulate` machine.
usage: power.py MACHINE.toml MODE FRAC FIRST LAST PLINTH...
MODE: prop-as-flat (noise sd FRAC*|X| per complex channel, columns = each
bearing-channel's RMS of it), flat-as-prop (noise sd FRAC*RMS, columns
proportional to |X| with the same RMS), small3 (noise FRAC*RMS, ped_y's column 3x
too small), true (noise FRAC*RMS, true columns). Noise complex, sd split on re/im.
Prints per seed and binary: per bearing rejected (shape) and max |z| of k,m if trusted."""
import csv, json, math, os, random, subprocess, sys
import tempfile
SCRATCH = os.environ.get("SCRATCH", os.path.join(tempfile.gettempdir(), "columns_null"))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the repository
# Scratch: $SCRATCH (default: the system temp directory + /columns_null; holds the recording REC/RUN of docs/estimation.md "Session 41 (lowsnr17)", ross/ runs, null draws).
machine, mode, frac, first, last = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
bins = sys.argv[6:]
tag = os.path.basename(machine).replace(".toml", "")
work = f"{SCRATCH}/pow-{tag}"; os.makedirs(work, exist_ok=True)
clean = f"{work}/clean"
if not os.path.exists(clean + "/measurements.csv"):
    subprocess.run([bins[0], "simulate", machine, "--out", clean], check=True, capture_output=True)
rows = list(csv.DictReader(open(clean + "/measurements.csv")))
CH = ["rel_y", "rel_z", "ped_y", "ped_z"]
mag = lambda r, c: math.hypot(float(r[c + "_re"]), float(r[c + "_im"]))
rms = {}
for b in {r["bearing"] for r in rows}:
    for c in CH:
        v = [mag(r, c) ** 2 for r in rows if r["bearing"] == b]
        rms[b, c] = math.sqrt(sum(v) / len(v))
for seed in range(first, last + 1):
    rng = random.Random(seed * 7919 + hash(mode) % 1000)
    d = f"{work}/{mode}-{frac}-{seed}"
    subprocess.run(["cp", "-r", clean, d])
    out_rows = []
    for r in rows:
        r = dict(r)
        for c in CH:
            flat = frac * rms[r["bearing"], c]
            true_sd = frac * mag(r, c) if mode == "prop-as-flat" else flat
            s = true_sd / math.sqrt(2)
            r[c + "_re"] = repr(float(r[c + "_re"]) + rng.gauss(0, s))
            r[c + "_im"] = repr(float(r[c + "_im"]) + rng.gauss(0, s))
            if mode == "prop-as-flat":
                col = flat
            elif mode == "flat-as-prop":
                col = max(frac * mag(r, c), 1e-6 * flat)  # |X| of the clean phasor, RMS = flat
            elif mode == "small3":
                col = flat / 3 if c == "ped_y" else flat
            else:
                col = flat
            r[c + "_sd"] = repr(col)
        out_rows.append(r)
    with open(d + "/measurements.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(out_rows[0].keys())); w.writeheader(); w.writerows(out_rows)
    truth = {p["bearing"]: p for p in json.load(open(d + "/truth.json"))["pedestals"]}
    for b in bins:
        out = subprocess.run(["nice", b, "identify", d, "--json"], capture_output=True, text=True)
        try:
            j = json.loads(out.stdout)
        except Exception:
            print(seed, b, "FAILED", out.stderr[-200:]); continue
        parts = []
        for p in j["pedestals"]:
            t = truth[p["bearing"]]
            rej = any("misdescribe" in x["message"] for x in p.get("warnings", []))
            zs = [abs(p[k] - t[k]) / p["std_err"][k] for k in ["k_y", "k_z", "m"] if p["std_err"].get(k)]
            parts.append(f"{p['bearing']} rej={int(rej)} tr={int(p['trusted'])} zkm={max(zs):.1f}")
        print(seed, "main" if "main" in b else "new", mode, frac, " | ".join(parts), flush=True)
    subprocess.run(["rm", "-rf", d])
