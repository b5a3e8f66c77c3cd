"""ROSS unseen runs with true noise columns: columns' shape rejected? ok beyond 3 ±?
usage: rossnull.py PLINTH -> one line per run."""
import glob, json, os, subprocess, sys
import tempfile
SCRATCH = os.environ.get("SCRATCH", os.path.join(tempfile.gettempdir(), "columns_null"))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the repository
# Scratch: $SCRATCH (default: the system temp directory + /columns_null; holds the recording REC/RUN of docs/estimation.md "Session 41 (lowsnr17)", ross/ runs, null draws).
plinth = sys.argv[1]
for d in sorted(glob.glob(os.path.join(SCRATCH, "ross", "*", "*-7??"))):
    if not os.path.exists(d + "/measurements.csv"):
        continue
    truth = {p["bearing"]: p for p in json.load(open(d + "/truth.json"))["pedestals"]}
    out = subprocess.run(["nice", plinth, "identify", d, "--json"], capture_output=True, text=True, env=dict(os.environ, LOWSNR17_TRACE="1"))
    try:
        j = json.loads(out.stdout)
    except Exception:
        print(d, "FAILED", out.stderr[-200:].replace("\n", " ")); continue
    parts = []
    for p in j["pedestals"]:
        t = truth.get(p["bearing"])
        rej = any("misdescribe" in x["message"] for x in p.get("warnings", []))
        zs = [abs(p[k] - t[k]) / p["std_err"][k] for k in ["k_y", "k_z", "m"] if t and p["std_err"].get(k)]
        parts.append(f"{p['bearing']} rej={int(rej)} tr={int(p['trusted'])} zkm={max(zs) if zs else 0:.1f}")
    ps = [l.split("p=")[1].split()[0] for l in out.stderr.splitlines() if l.startswith("TRACE")]
    print(d.split("/ross/")[1], " | ".join(parts), "P", ",".join(ps), flush=True)
