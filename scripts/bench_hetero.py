#!/usr/bin/env python3
"""Issue 17, heteroscedastic noise without noise columns (docs/trust-noise-law.md): Monte-Carlo
of identify on ROSS unseen-overhung clean-h1 / clean-h1c runs made by
`scripts/ross_unseen.py --machine unseen-overhung RUNS clean-h1,clean-h1c 1 ... N`.
Usage: bench_hetero.py PLINTH RUNS_DIR SEEDS [VARIANTS] -> per variant: ok-but-wrong counts,
RMS and mean of (estimate - truth)/std_err per parameter, and how often the fit's residuals
rejected the noise columns' shape (host/src/estimate/noise/columns.rs: `variance_function`
under source `columns`; on h1c a false alarm, on h1c-const a detection). Variants: h1 (no
columns), h1c (true-law columns), h1t (h1's readings with their true columns, taken from clean-h1c seed 1: the same
noise draws under known weights), h1c-const (each bearing-channel's RMS sd as a constant column), h1c-mixW (each
column W of the way in sd from that RMS to the true one: h1c-mix0.5 half-way); needing
clean-d12 seed 1 in RUNS_DIR: h1v (the machine's noise plus a pick-up's velocity floor
1 um/s / Omega on the pedestal channels, true columns), h1v-const (its RMS sd as constant
columns), h1v-law (columns of the machine's law without the velocity floor), h1v-mixW.

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
    ps = [n["variance_function"]["p_value"] for j in idents for b, n in j["noise"].items()
          if b in rejected(j)]
    top = f", largest p of a rejection {max(ps):.1e}" if ps else ""
    return (f"{name}: columns' shape rejected in {runs_hit}/{len(idents)} runs, "
            f"{hits}/{fits} bearing fits with columns{top}")


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
if len(sys.argv) < 4 or sys.argv[1] in ("-h", "--help"):
    print(__doc__)
    sys.exit(0 if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help") else 2)
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


def true_columns_copy(src, cols, dst):
    """src (a clean-h1 run: readings, no columns) with the *_sd columns of cols (clean-h1c
    seed 1): the same noise draw under its true law. The true sd depends only on the noiseless
    response and the speed grid, which clean-h1 and clean-h1c share at every seed."""
    os.makedirs(dst, exist_ok=True)
    for f in ("bearings.csv", "truth.json"):
        shutil.copy(os.path.join(src, f), dst)
    rows = list(csv.DictReader(open(os.path.join(src, "measurements.csv"))))
    crow = list(csv.DictReader(open(os.path.join(cols, "measurements.csv"))))
    sdc = [c for c in crow[0] if c.endswith("_sd")]
    with open(os.path.join(dst, "measurements.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]) + sdc)
        w.writeheader()
        for r, c in zip(rows, crow):
            if (r["speed_hz"], r["bearing"]) != (c["speed_hz"], c["bearing"]):
                sys.exit(f"{src} and {cols}: rows differ ({r['speed_hz']} {r['bearing']})")
            r.update({k: c[k] for k in sdc})
            w.writerow(r)


def h1t(s):
    d = os.path.join(runs, f"clean-h1t-{s}")
    if not os.path.isdir(d):
        true_columns_copy(os.path.join(runs, f"clean-h1-{s}"), os.path.join(runs, "clean-h1c-1"), d)
    return d
# h1's own noise draws with their true columns: what the scatter path's variance function
# costs against known weights, draw for draw (needs clean-h1c seed 1 in RUNS).
variants["h1t"] = h1t

# Noise of another shape than the variance function's family (a fraction of |X| plus a
# floor): the machine's noise plus a seismic pick-up's velocity floor on the pedestal
# channels, VEL [m/s] / Omega in displacement (1 um/s, unseen-flex's pick-ups in
# scripts/ross_unseen.py), added here to ROSS's noiseless clean-d12 seed 1 (the same
# coast-down grid as clean-h1) with a seed of this script's own.
VEL = 1e-6


def shaped_copy(src, dst, seed, noise_sd, columns):
    """dst: src's readings (noiseless) plus complex Gaussian noise of sd noise_sd(channel,
    |X| array, speeds) [m], with the columns columns(true sd array) (None: the machine's
    law without the velocity floor)."""
    import numpy as np
    os.makedirs(dst, exist_ok=True)
    for f in ("bearings.csv", "truth.json"):
        shutil.copy(os.path.join(src, f), dst)
    rows = list(csv.DictReader(open(os.path.join(src, "measurements.csv"))))
    chans = ("rel_y", "rel_z", "ped_y", "ped_z")
    rng = np.random.default_rng(31_000 + seed)
    out = {id(r): dict(r) for r in rows}
    for b in sorted({r["bearing"] for r in rows}):
        mine = [r for r in rows if r["bearing"] == b]
        speeds = np.array([float(r["speed_hz"]) for r in mine])
        for c in chans:
            v = np.array([complex(float(r[c + "_re"]), float(r[c + "_im"])) for r in mine])
            sd = noise_sd(c, np.abs(v), speeds)
            v0 = v
            v = v + (rng.standard_normal(len(v)) + 1j * rng.standard_normal(len(v))) * sd / math.sqrt(2)
            col = columns(sd) if columns else velocity_floor("rel", np.abs(v0), speeds)
            for r, q, s in zip(mine, v, col):
                o = out[id(r)]
                o[c + "_re"], o[c + "_im"], o[c + "_sd"] = f"{q.real:.6e}", f"{q.imag:.6e}", f"{s:.3e}"
    names = list(rows[0]) + [c + "_sd" for c in chans]
    with open(os.path.join(dst, "measurements.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=names)
        w.writeheader()
        for r in rows:
            w.writerow(out[id(r)])


def velocity_floor(c, mag, speeds):
    """The machine's law (1 % of |X| + 0.1 % of the channel's RMS) plus VEL / Omega on the
    pedestal pick-ups [m]."""
    import numpy as np
    sd = 0.01 * mag + 0.001 * math.sqrt(float(np.mean(mag ** 2)))
    return sd + (VEL / (2 * math.pi * speeds) if c.startswith("ped") else 0.0)


def rms_of(sd):
    return [math.sqrt(sum(x * x for x in sd) / len(sd))] * len(sd)


def mixed(w):
    """Columns w of the way (in sd) from their RMS (w = 0, constant) to the true ones (w = 1)."""
    def cols(sd):
        r = rms_of(sd)[0]
        return [w * x + (1 - w) * r for x in sd]
    return cols


def shaped(name, columns):
    def at(s):
        d = os.path.join(runs, f"clean-{name}-{s}")
        if not os.path.isdir(d):
            shaped_copy(os.path.join(runs, "clean-d12-1"), d, s, velocity_floor, columns)
        return d
    return at


def mix_copy(src, dst, w):
    """src with each column w of the way from its bearing-channel RMS to its true sd."""
    os.makedirs(dst, exist_ok=True)
    for f in ("bearings.csv", "truth.json"):
        shutil.copy(os.path.join(src, f), dst)
    rows = list(csv.DictReader(open(os.path.join(src, "measurements.csv"))))
    sdc = [c for c in rows[0] if c.endswith("_sd")]
    for b in {r["bearing"] for r in rows}:
        for c in sdc:
            mine = [r for r in rows if r["bearing"] == b]
            for r, x in zip(mine, mixed(w)([float(r[c]) for r in mine])):
                r[c] = f"{x:.3e}"
    with open(os.path.join(dst, "measurements.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def h1c_mix(w):
    def at(s):
        d = os.path.join(runs, f"clean-h1c-mix{w}-{s}")
        if not os.path.isdir(d):
            mix_copy(os.path.join(runs, f"clean-h1c-{s}"), d, w)
        return d
    return at


variants["h1v"] = shaped("h1v", lambda sd: list(sd))
variants["h1v-const"] = shaped("h1v-const", rms_of)
# The machine's law as columns, the pick-up's velocity floor left out of them.
variants["h1v-law"] = shaped("h1v-law", None)


def variant(name):
    """A named variant, or h1c-mixW / h1v-mixW: columns W (0..1) of the way from constant to
    true (h1c-mix0.5: half-way)."""
    if name.startswith("h1c-mix"):
        return h1c_mix(float(name[len("h1c-mix"):]))
    if name.startswith("h1v-mix"):
        w = float(name[len("h1v-mix"):])
        return shaped(f"h1v-mix{w}", mixed(w))
    return variants[name]
for name in (sys.argv[4].split(",") if len(sys.argv) > 4 else variants):
    at = variant(name)
    both = [run(at(s)) for s in range(1, seeds + 1)]
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
