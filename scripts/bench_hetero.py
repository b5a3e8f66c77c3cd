#!/usr/bin/env python3
"""Issue 17, heteroscedastic noise without noise columns (docs/trust.md): Monte-Carlo
of identify on ROSS unseen-overhung clean-h1 / clean-h1c runs made by
`scripts/ross_unseen.py --machine unseen-overhung RUNS clean-h1,clean-h1c 1 ... N`.
Usage: bench_hetero.py PLINTH RUNS_DIR SEEDS [VARIANTS] -> per variant: ok-but-wrong counts,
RMS and mean of (estimate - truth)/std_err per parameter, and how often the fit's residuals
rejected the noise columns' shape (host/src/estimate/noise/columns.rs: `variance_function`
under source `columns`; on h1c a false alarm, on h1c-const a detection). Variants: h1 (no
columns), h1c (true-law columns), h1c-const (each bearing-channel's RMS sd as a constant column).

Also: bench_hetero.py --rejections PLINTH DIR...  counts the columns' shape rejected over any
run directories (e.g. scripts/ross_unseen.py's clean-n1c, clean-w1c, clean-p2c);
bench_hetero.py --rejections-sim PLINTH RUNS  the same over scripts/bench_common.py's clean
cases with noise columns (the paper machine and the three-bearing machine, 1 % + columns,
RUNS seeds each: the data of `scripts/bench-trust.sh RUNS columns`)."""
import csv, json, math, os, subprocess, sys, shutil
P = ["k_y", "k_z", "m", "c_y", "c_z"]


def rejected(j):
    """Bearings whose noise columns' shape the fit's residuals rejected."""
    return [b for b, n in j["noise"].items()
            if n["source"] == "columns" and n.get("variance_function")]


def rejection_line(name, idents):
    """Runs and bearing fits with the columns' shape rejected, over identify JSONs."""
    fits = sum(sum(n["source"] == "columns" for n in j["noise"].values()) for j in idents)
    runs_hit = sum(bool(rejected(j)) for j in idents)
    hits = sum(len(rejected(j)) for j in idents)
    return (f"{name}: columns' shape rejected in {runs_hit}/{len(idents)} runs, "
            f"{hits}/{fits} bearing fits with columns")


if len(sys.argv) > 2 and sys.argv[1] in ("--rejections", "--rejections-sim"):
    if sys.argv[1] == "--rejections":
        idents = []
        for d in sys.argv[3:]:
            out = subprocess.run([sys.argv[2], "identify", "--json", d], capture_output=True,
                                 text=True)
            idents.append(json.loads(out.stdout))
            if rejected(idents[-1]):
                print(f"  rejected: {d} {rejected(idents[-1])}")
        print(rejection_line("directories", idents))
    else:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import bench_common as bc
        pl = bc.Plinth(sys.argv[2], "bench-hetero-")
        try:
            for case, n, results in bc.clean_identifications(pl, int(sys.argv[3]), "columns"):
                for seed, j, _ in results:
                    if rejected(j):
                        print(f"  rejected: {case} seed {seed} {rejected(j)}")
                print(rejection_line(case, [j for _, j, _ in results]))
        finally:
            pl.close()
    sys.exit(0)
plinth, runs, seeds = sys.argv[1], sys.argv[2], int(sys.argv[3])

def const_copy(src, dst):
    os.makedirs(dst, exist_ok=True)
    for f in ("bearings.csv", "truth.json"):
        shutil.copy(os.path.join(src, f), dst)
    rows = list(csv.DictReader(open(os.path.join(src, "measurements.csv"))))
    sdc = [c for c in rows[0] if c.endswith("_sd")]
    rms = {}
    for b in {r["bearing"] for r in rows}:
        for c in sdc:
            v = [float(r[c]) ** 2 for r in rows if r["bearing"] == b]
            rms[b, c] = math.sqrt(sum(v) / len(v))
    with open(os.path.join(dst, "measurements.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            for c in sdc:
                r[c] = f"{rms[r['bearing'], c]:.3e}"
            w.writerow(r)

def run(d):
    out = subprocess.run([plinth, "identify", "--json", d], capture_output=True, text=True)
    j = json.loads(out.stdout)
    truth = {t["bearing"]: t for t in json.load(open(os.path.join(d, "truth.json")))["pedestals"]}
    res = []
    for p in j["pedestals"]:
        t = truth[p["bearing"]]
        z = {k: (p[k] - t[k]) / p["std_err"][k] for k in P}
        res.append((p["bearing"], p["trusted"], z, j["noise"]))
    return res, j

variants = {"h1": lambda s: os.path.join(runs, f"clean-h1-{s}"),
            "h1c": lambda s: os.path.join(runs, f"clean-h1c-{s}")}
def constd(s):
    d = os.path.join(runs, f"clean-h1c-const-{s}")
    if not os.path.isdir(d):
        const_copy(os.path.join(runs, f"clean-h1c-{s}"), d)
    return d
variants["h1c-const"] = constd
for name in (sys.argv[4].split(",") if len(sys.argv) > 4 else variants):
    both = [run(variants[name](s)) for s in range(1, seeds + 1)]
    rs = [r for r, _ in both]
    okw_km = sum(any(t and max(abs(z[k]) for k in P[:3]) > 3 for _, t, z, _ in r) for r in rs)
    okw_all = sum(any(t and max(abs(z[k]) for k in P) > 3 for _, t, z, _ in r) for r in rs)
    untr = sum(any(not t for _, t, _, _ in r) for r in rs)
    print(f"{name}: {len(rs)} runs; runs with an ok pedestal > 3 ± off: k/m {okw_km}, any parameter {okw_all}; runs with an untrusted bearing {untr}")
    print("  " + rejection_line(name, [j for _, j in both]))
    for b in ("B1", "B2"):
        zs = [z for r in rs for bb, _, z, _ in r if bb == b]
        rms = "  ".join(f"{k} {math.sqrt(sum(z[k] ** 2 for z in zs) / len(zs)):.2f}" for k in P)
        mean = "  ".join(f"{k} {sum(z[k] for z in zs) / len(zs):+.2f}" for k in P)
        print(f"  {b} RMS z: {rms}\n  {b} mean z: {mean}")
