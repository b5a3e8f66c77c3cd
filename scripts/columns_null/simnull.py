"""Null Monte-Carlo of the columns' shape test on a `plinth simulate` machine:
white noise of FRAC of each bearing-channel's RMS (plinth simulate --noise) with
the true columns (FRAC x the clean RMS) written into measurements.csv.
usage: simnull.py MACHINE.toml FIRST LAST PLINTH [FRAC] -> one line per seed:
seed, per bearing: rejected (noise_scale_mismatch), trusted, max |z|."""
import csv, json, math, os, subprocess, sys
import tempfile
SCRATCH = os.environ.get("SCRATCH", os.path.join(tempfile.gettempdir(), "columns_null"))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the repository
# Scratch: $SCRATCH (default: the system temp directory + /columns_null; holds the recording REC/RUN of docs/estimation.md "Session 41 (lowsnr17)", ross/ runs, null draws).
machine, first, last, plinth = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
frac = float(sys.argv[5]) if len(sys.argv) > 5 else 0.01
tag = os.path.basename(machine).replace(".toml", "")
work = f"{SCRATCH}/sim-{tag}"; os.makedirs(work, exist_ok=True)
clean = f"{work}/clean"
if not os.path.exists(clean + "/measurements.csv"):
    subprocess.run([plinth, "simulate", machine, "--out", clean], check=True, capture_output=True)
rows = list(csv.DictReader(open(clean + "/measurements.csv")))
sd = {}
for b in sorted({r["bearing"] for r in rows}):
    for ch in ["rel_y", "rel_z", "ped_y", "ped_z"]:
        ms = [float(r[ch + "_re"]) ** 2 + float(r[ch + "_im"]) ** 2 for r in rows if r["bearing"] == b]
        sd[b, ch] = frac * math.sqrt(sum(ms) / len(ms))
for seed in range(first, last + 1):
    d = f"{work}/s{seed}"
    subprocess.run([plinth, "simulate", machine, "--out", d, "--noise", str(frac), "--seed", str(seed)], check=True, capture_output=True)
    m = list(csv.DictReader(open(d + "/measurements.csv")))
    names = list(m[0].keys()) + [c + "_sd" for c in ["rel_y", "rel_z", "ped_y", "ped_z"]]
    with open(d + "/measurements.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=names); w.writeheader()
        for r in m:
            for c in ["rel_y", "rel_z", "ped_y", "ped_z"]:
                r[c + "_sd"] = repr(sd[r["bearing"], c])
            w.writerow(r)
    truth = {p["bearing"]: p for p in json.load(open(d + "/truth.json"))["pedestals"]}
    out = subprocess.run(["nice", plinth, "identify", d, "--json"], capture_output=True, text=True, env=dict(os.environ, LOWSNR17_TRACE="1"))
    j = json.loads(out.stdout)
    parts = []
    for p in j["pedestals"]:
        t = truth[p["bearing"]]
        rej = any("misdescribe" in x["message"] for x in p.get("warnings", []))
        zs = [abs(p[k] - t[k]) / p["std_err"][k] for k in ["k_y", "k_z", "m", "c_y", "c_z"] if p["std_err"].get(k)]
        parts.append(f"{p['bearing']} rej={int(rej)} tr={int(p['trusted'])} zmax={max(zs):.1f}")
    ps = [l.split("p=")[1].split()[0] for l in out.stderr.splitlines() if l.startswith("TRACE")]
    print(seed, " | ".join(parts), "P", ",".join(ps), flush=True)
    subprocess.run(["rm", "-rf", d])
