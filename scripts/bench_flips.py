#!/usr/bin/env python3
"""Monte-Carlo of identify's keyphasor-flip detection (run by
scripts/bench-flips.sh).

False alarms: the clean cases of scripts/bench_trust.py (the undamped paper
machine and the three-bearing machine with tabulated bearings; digits 2/3/12
on shifted speed grids, white noise 0.3/1/3 %, heteroscedastic noise 2 % of
|phasor|, noise 1 % with noise columns, noise 1 % at 3 digits). A run is a
false alarm when any pedestal carries a `keyphasor_flip` warning. Printed:
runs, flagged runs, the rate and its one-sided 95 % upper bound
(Clopper-Pearson).

Detections (three-bearing machine, bearing `mid`, 1 % noise): three random
flipped speeds (the protocol of bench_trust.py: speeds 25-192.5 Hz), two and
three adjacent ones at a random place, and the pair 40/42.5 Hz next to
`mid`'s resonance. A run is a hit when `noise.mid.outlier_speeds_hz` is
exactly the flipped speeds and no other bearing lists a speed.

Other machines (not tuned to): the ROSS reference machines c (three
bearings on a skid and frame) and d (B1 on its own sub-base) and the
three-bearing machine on a frame, 1 % noise: clean runs with a
`keyphasor_flip` warning, and three random flipped speeds of each bearing in
turn (a hit: every flipped speed listed for that bearing, no flipped speed
listed for another; extra speeds listed are counted apart, since the
outlier and lack-of-fit tests list these machines' model error).

Every bearing flipped (the machine's keyphasor): three random speeds of the
three-bearing machine with every channel of every bearing negated (made
here from trust_data.py's noisy run); a hit when every bearing lists
exactly those speeds, with the note that every bearing lists them.

Sections: BENCH_SECTIONS=clean,detect,other,every (default all; a CASE_FILTER
runs the clean cases only).

Test data: `plinth simulate` (exact, 12 digits) and scripts/trust_data.py
(noise, digits, columns, --flip), independent of the estimator. The clean
cases, the runners and the bound are scripts/bench_common.py's (one
definition with bench_trust.py).

usage: bench_flips.py PLINTH_BINARY [RUNS_PER_CASE] [CASE_FILTER]
"""
import csv
import os
import random
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

SECTIONS = os.environ.get("BENCH_SECTIONS", "clean,detect,other,every").split(",")
GRID = bc.GRID
THREE = bc.THREE
ROOT = bc.ROOT


def flip_named(ident):
    """The bearings identify warns of a keyphasor flip at."""
    return [p["bearing"] for p in ident["pedestals"]
            if any(w["kind"] == "keyphasor_flip" for w in p["warnings"])]


def false_alarms(pl, n, only):
    print("FALSE ALARMS: runs with a keyphasor_flip warning on clean data")
    print(f"{'case':36s} {'runs':>5s} {'flagged':>7s} {'%':>6s} {'≤95%up':>7s}")
    total = flagged_total = 0
    for case, runs, results in bc.clean_identifications(pl, n, only):
        k = 0
        for seed, ident, _ in results:
            named = flip_named(ident)
            if named:
                k += 1
                print(f"    flagged: {case} seed {seed}: {named}", flush=True)
        print(f"{case:36s} {runs:5d} {k:7d} {100.0 * k / runs:6.2f}"
              f" {100.0 * bc.upper95(k, runs):7.2f}", flush=True)
        total += runs
        flagged_total += k
    if total:
        print(f"{'ALL CLEAN RUNS':36s} {total:5d} {flagged_total:7d}"
              f" {100.0 * flagged_total / total:6.2f}"
              f" {100.0 * bc.upper95(flagged_total, total):7.2f}")


def detections(pl, N):
    print("\nDETECTIONS (three-bearing, `mid`, 1 % noise): flipped speeds listed exactly")
    exact = pl.path("exact-three")
    pl.sim(THREE, exact, "--digits", "12")
    n = max(N // 5, 20)

    def speeds_for(kind, seed):
        rng = random.Random(seed)
        if kind == "3 random":
            return sorted(rng.sample(GRID[8:76], 3))
        if kind == "2 adjacent":
            i = rng.randrange(8, 75)
            return GRID[i:i + 2]
        if kind == "3 adjacent":
            i = rng.randrange(8, 74)
            return GRID[i:i + 3]
        return [40.0, 42.5]

    for kind in ("3 random", "2 adjacent", "3 adjacent", "40/42.5 Hz"):
        def one(seed, kind=kind):
            speeds = speeds_for(kind, seed)
            out = pl.path(f"flip-{seed}")
            bc.data(exact, out, "--noise", "0.01", "--seed", str(seed),
                 "--flip", "mid:" + ",".join(f"{s:g}" for s in speeds))
            ident, _ = pl.identify(out)
            subprocess.run(["rm", "-rf", out], check=True)
            ok = sorted(bc.listed(ident, "mid")) == speeds
            ok &= all(not bc.listed(ident, p["bearing"]) for p in ident["pedestals"]
                      if p["bearing"] != "mid")
            return seed, speeds, ok, bc.listed(ident, "mid")

        results = bc.parallel(one, range(1, n + 1))
        hits = 0
        for seed, speeds, ok, got in results:
            hits += ok
            if not ok:
                print(f"    missed: {kind} seed {seed}: flipped {speeds}, listed {got}", flush=True)
        print(f"  {kind:12s}: listed exactly in {hits}/{n} runs", flush=True)


OTHERS = [
    ("ross-c", os.path.join(ROOT, "tests", "reference", "ross", "machine-c.toml")),
    ("ross-d", os.path.join(ROOT, "tests", "reference", "ross", "machine-d.toml")),
    ("on-frame", os.path.join(ROOT, "tests", "machines", "three-pedestals-on-frame.toml")),
]


def other_machines(pl, N):
    print("\nOTHER MACHINES (1 % noise): clean runs with a keyphasor_flip warning;"
          " 3 random flipped speeds of each bearing")
    n = max(N // 5, 20)
    for mname, machine in OTHERS:
        exact = pl.path(f"exact-{mname}")
        pl.sim(machine, exact, "--digits", "12")

        def clean(seed, mname=mname, exact=exact):
            out = pl.path(f"other-{mname}-{seed}")
            bc.data(exact, out, "--noise", "0.01", "--seed", str(seed))
            ident, _ = pl.identify(out)
            subprocess.run(["rm", "-rf", out], check=True)
            return seed, flip_named(ident)

        results = bc.parallel(clean, range(1, N + 1))
        k = sum(1 for _, named in results if named)
        for seed, named in results:
            if named:
                print(f"    flagged: {mname} seed {seed}: {named}", flush=True)
        print(f"  {mname} clean: {k}/{N} runs name a flip (95 % upper bound"
              f" {100.0 * bc.upper95(k, N):.2f} %)", flush=True)
        bearings = [p["bearing"] for p in pl.identify(exact)[0]["pedestals"]]
        for bearing in bearings:
            def one(seed, bearing=bearing, exact=exact, mname=mname):
                speeds = sorted(random.Random(seed).sample(GRID[8:76], 3))
                out = pl.path(f"other-flip-{mname}-{seed}")
                bc.data(exact, out, "--noise", "0.01", "--seed", str(seed),
                     "--flip", bearing + ":" + ",".join(f"{s:g}" for s in speeds))
                ident, _ = pl.identify(out)
                subprocess.run(["rm", "-rf", out], check=True)
                got = bc.listed(ident, bearing)
                hit = all(s in got for s in speeds)
                hit &= all(not (set(speeds) & set(bc.listed(ident, p["bearing"])))
                           for p in ident["pedestals"] if p["bearing"] != bearing)
                extra = [s for s in got if s not in speeds]
                return seed, speeds, hit, got, extra

            results = bc.parallel(one, range(1, n + 1))
            hits = sum(r[2] for r in results)
            extras = sum(1 for r in results if r[4])
            for seed, speeds, hit, got, _ in results:
                if not hit:
                    print(f"    missed: {mname} {bearing} seed {seed}: flipped {speeds},"
                          f" listed {got}", flush=True)
            print(f"  {mname} {bearing}: 3 random flips named in {hits}/{n} runs"
                  f" ({extras} runs list other speeds too)", flush=True)


def negate_every_bearing(run, speeds):
    """Negates every phasor of every bearing of `run` at `speeds` [Hz]."""
    path = os.path.join(run, "measurements.csv")
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        if float(r["speed_hz"]) in speeds:
            for k in r:
                if k.endswith("_re") or k.endswith("_im"):
                    r[k] = repr(-float(r[k]))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def every_bearing(pl, N):
    print("\nEVERY BEARING FLIPPED (three-bearing, 1 % noise, 3 random speeds):"
          " listed exactly at every bearing")
    exact = pl.path("exact-three-every")
    pl.sim(THREE, exact, "--digits", "12")
    n = max(N // 5, 20)

    def one(seed):
        speeds = sorted(random.Random(seed).sample(GRID[8:76], 3))
        out = pl.path(f"every-{seed}")
        bc.data(exact, out, "--noise", "0.01", "--seed", str(seed))
        negate_every_bearing(out, speeds)
        ident, _ = pl.identify(out)
        subprocess.run(["rm", "-rf", out], check=True)
        got = {p["bearing"]: bc.listed(ident, p["bearing"]) for p in ident["pedestals"]}
        noted = all(any("every bearing lists" in w["message"] for w in p["warnings"])
                    for p in ident["pedestals"])
        wrong = any(s not in speeds for g in got.values() for s in g)
        return seed, speeds, all(g == speeds for g in got.values()) and noted, wrong, got

    results = bc.parallel(one, range(1, n + 1))
    for seed, speeds, hit, _, got in results:
        if not hit:
            print(f"    missed: seed {seed}: flipped {speeds}, listed {got}", flush=True)
    print(f"  listed exactly at every bearing, noted: {sum(r[2] for r in results)}/{n};"
          f" runs listing a speed not flipped: {sum(r[3] for r in results)}", flush=True)


def main(argv=None):
    binary, n, only = bc.arguments(argv)
    pl = bc.Plinth(binary, "bench-flips-")
    try:
        if "clean" in SECTIONS:
            false_alarms(pl, n, only)
        if not only and "detect" in SECTIONS:
            detections(pl, n)
        if not only and "other" in SECTIONS:
            other_machines(pl, n)
        if not only and "every" in SECTIONS:
            every_bearing(pl, n)
    finally:
        pl.close()


if __name__ == "__main__":
    main()
