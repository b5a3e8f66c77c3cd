"""Null draws of the unseen-train recording: columns rejected? B1 trusted and > 3 ± off?
usage: nullrun.py FIRST LAST PLINTH... ; prints one line per seed and binary."""
import json, subprocess, sys, os
import tempfile
SCRATCH = os.environ.get("SCRATCH", os.path.join(tempfile.gettempdir(), "columns_null"))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # the repository
# Scratch: $SCRATCH (default: the system temp directory + /columns_null; holds the recording REC/RUN of docs/estimation.md "Session 41 (lowsnr17)", ross/ runs, null draws).
first, last = int(sys.argv[1]), int(sys.argv[2]); bins = sys.argv[3:]
PY = os.environ.get("PYTHON", "python3")  # one with ROSS 2.3.0; SCRIPT = os.path.join(ROOT, "scripts", "ross_recording.py")
os.chdir(SCRATCH)
for seed in range(first, last + 1):
    d = f"nulls/NULL-{seed}"
    if not os.path.exists(d + "/measurements.csv"):
        os.makedirs("nulls", exist_ok=True)
        subprocess.run([PY, SCRIPT, "--null", "RUN", "REC", d, str(seed)], check=True, capture_output=True)
    truth = {p["bearing"]: p for p in json.load(open(d + "/truth.json"))["pedestals"]}
    for b in bins:
        out = subprocess.run(["nice", b, "identify", d, "--json"], capture_output=True, text=True, env=dict(os.environ, LOWSNR17_TRACE="1"))
        j = json.loads(out.stdout)
        parts = []
        for p in j["pedestals"]:
            name = p["bearing"]; t = truth[name]
            rej = any("misdescribe" in w["message"] for w in p.get("warnings", []))
            z = {k: (p[k] - t[k]) / p["std_err"][k] for k in ["k_y", "k_z", "m", "c_y", "c_z"] if p["std_err"].get(k)}
            zmax = max(abs(v) for v in z.values())
            parts.append(f"{name} rej={int(rej)} tr={int(p['trusted'])} ky={100*(p['k_y']/t['k_y']-1):+.1f}% m={100*(p['m']/t['m']-1):+.0f}% zk={z['k_y']:+.1f},{z['k_z']:+.1f} zm={z['m']:+.1f} zmax={zmax:.1f}")
        ps = [l.split("p=")[1].split()[0] for l in out.stderr.splitlines() if l.startswith("TRACE")]
        print(seed, "main" if "main" in b else "new", " | ".join(parts), "P", ",".join(ps), flush=True)
