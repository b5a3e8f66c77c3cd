#!/usr/bin/env python3
"""Monte-Carlo of identify's trust rules (run by scripts/bench-trust.sh).

False alarms: clean runs (the paper's undamped machine, whose pedestal
damping is truly zero, and a three-bearing machine with cross-coupled
tabulated bearings) at digits 2/3/12, white noise of several levels,
heteroscedastic noise and noise columns. A run is a false alarm for a rule
when any of its pedestals carries that rule's warning (lack_of_fit,
physically_impossible, suspected_convention_error, implausible), lists an
outlier speed (outlier_speeds_hz: robust fit or keyphasor flip), or
`plinth identify` exits 2.

Detections: the faults each rule is for: a pedestal on its own sub-base
(three machines), three speeds with one bearing's phasors flipped by 180°,
pedestal pick-ups in um against probes in m, only the pedestal phasors
conjugated, absurd magnitudes.

Test data come from `plinth simulate` (the simulator's elements, its
`pedestal_sub_base` effect and machine-file `sub_base`) and
scripts/trust_data.py (noise, columns, faults), not from the estimator.

Each row prints the flagged % per rule and, for the run-level verdict
("any"), the one-sided 95 % upper bound of the false-alarm rate
(Clopper-Pearson). Runs go in parallel over $BENCH_JOBS workers (default:
the CPU count).

usage: bench_trust.py PLINTH_BINARY [RUNS_PER_CASE] [CASE_FILTER]
  CASE_FILTER: run only the false-alarm cases whose name contains it (and
  no detections), e.g. "paper-undamped hetero".
"""
import concurrent.futures
import json
import os
import math
import random
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
B = sys.argv[1]
N = int(sys.argv[2]) if len(sys.argv) > 2 else 100
ONLY = sys.argv[3] if len(sys.argv) > 3 else ""
JOBS = int(os.environ.get("BENCH_JOBS", os.cpu_count() or 1))
DATA = os.path.join(ROOT, "scripts", "trust_data.py")
PAPER = os.path.join(ROOT, "examples", "feng-hahn-1997.toml")
THREE = os.path.join(ROOT, "tests", "machines", "three-bearing-tabulated.toml")
SUB = os.path.join(ROOT, "tests", "machines", "three-bearing-sub-base.toml")
ROSS_D = os.path.join(ROOT, "tests", "reference", "ross", "machine-d.toml")
RULES = ["lack_of_fit", "physically_impossible", "suspected_convention_error",
         "implausible", "outliers_listed", "exit_2"]
W = tempfile.mkdtemp(prefix="bench-trust-")
SPEEDS = "5:200:2.5"


def sim(machine, out, *args, speeds=SPEEDS):
    subprocess.run(["rm", "-rf", out], check=True)
    subprocess.run([B, "simulate", machine, "--out", out, "--speeds", speeds, *args],
                   check=True, stdout=subprocess.DEVNULL)


def data(src, out, *args):
    subprocess.run(["rm", "-rf", out], check=True)
    subprocess.run([sys.executable, DATA, src, out, *args], check=True)


def grid(seed):
    """A speed grid of the digit cases: first speed and step drawn from `seed`."""
    r = random.Random(seed)
    first, step = 5 + 2.5 * r.random(), 2.5 * (0.95 + 0.1 * r.random())
    return f"{first:.4f}:200:{step:.4f}"


def identify(run):
    p = subprocess.run([B, "identify", run, "--json"], capture_output=True, text=True)
    if p.returncode not in (0, 2):
        raise RuntimeError(f"identify {run}: exit {p.returncode}: {p.stderr}")
    return json.loads(p.stdout), p.returncode


def listed(ident, bearing):
    """The speeds identify lists as bad for `bearing` (noise.<b>.outlier_speeds_hz)."""
    return ident["noise"].get(bearing, {}).get("outlier_speeds_hz", [])


def flags(ident, code):
    got = {r: False for r in RULES}
    for p in ident["pedestals"]:
        for w in p["warnings"]:
            if w["kind"] in got:
                got[w["kind"]] = True
        if listed(ident, p["bearing"]):
            got["outliers_listed"] = True
    got["exit_2"] = code == 2
    return got


def lack_of_fit_figures(ident):
    """(largest level ratio, smallest structure p) over the judged bearings."""
    level, p = 0.0, 1.0
    for n in ident["noise"].values():
        lof = n.get("lack_of_fit")
        if lof:
            level = max(level, lof["level_ratio"])
            if lof.get("structure"):
                p = min(p, lof["structure"]["p_value"])
    return level, p


def upper95(k, n):
    """One-sided 95 % Clopper-Pearson upper bound of a rate seen k times in n."""
    if n == 0:
        return 1.0
    if k >= n:
        return 1.0
    lo, hi = k / n, 1.0
    for _ in range(60):  # bisection on P(X <= k | p) = 0.05
        mid = 0.5 * (lo + hi)
        cdf = sum(math.comb(n, i) * mid ** i * (1 - mid) ** (n - i) for i in range(k + 1))
        lo, hi = (mid, hi) if cdf > 0.05 else (lo, mid)
    return hi


def row(case, runs, counts, extremes=None):
    cells = "  ".join(f"{100.0 * counts[r] / max(runs, 1):6.2f}" for r in RULES)
    anyc = counts["any"]
    ext = f"  {extremes[0]:8.3f} {extremes[1]:8.4f}" if extremes else ""
    print(f"{case:34s} {runs:5d}  {cells}  {100.0 * anyc / max(runs, 1):6.2f}"
          f" {100.0 * upper95(anyc, runs):6.2f}{ext}", flush=True)


def header(title):
    print(f"\n{title}")
    print(f"{'case':34s} {'runs':>5s}  " + "  ".join(f"{r[:6]:>6s}" for r in RULES)
          + "     any  ≤95%up  maxlevel  min p")
    print(f"{'':34s} {'':5s}  " + "  ".join(f"{'%':>6s}" for _ in RULES))


def false_alarms():
    header("FALSE ALARMS per run on clean data (flagged %, by rule)")
    total = {r: 0 for r in RULES + ["any"]}
    total_runs = 0
    for mname, machine in (("paper-undamped", PAPER), ("three-bearing", THREE)):
        exact = os.path.join(W, "exact")
        sim(machine, exact, "--digits", "12")
        # Digits alone are deterministic: each run draws its own speed grid
        # (first speed 5-7.5 Hz, step 2.375-2.625 Hz, from the seed), so that
        # runs differ in where the speeds fall on the resonances.
        cases = [(f"{mname} digits {d}", N, ("sim", "--digits", d))
                 for d in ("2", "3", "12")]
        cases += [
            (f"{mname} noise 0.3 %", N, ("data", "--noise", "0.003")),
            (f"{mname} noise 1 %", N, ("data", "--noise", "0.01")),
            (f"{mname} noise 3 %", N, ("data", "--noise", "0.03")),
            (f"{mname} hetero 2 % of |phasor|", max(N, 200),
             ("data", "--relative-noise", "0.02")),
            (f"{mname} noise 1 % + columns", N, ("data", "--noise", "0.01", "--columns")),
            (f"{mname} noise 1 % at 3 digits", N, ("data", "--noise", "0.01", "--digits", "3")),
        ]
        for case, runs, how in cases:
            if ONLY not in case:
                continue
            counts = {r: 0 for r in RULES + ["any"]}
            extremes = [0.0, 1.0]

            def one(seed, case=case, how=how, machine=machine):
                out = os.path.join(W, f"clean-{seed}")
                if how[0] == "sim":
                    sim(machine, out, *how[1:], speeds=grid(seed))
                else:
                    data(exact, out, *how[1:], "--seed", str(seed))
                ident, code = identify(out)
                subprocess.run(["rm", "-rf", out], check=True)
                return seed, ident, code

            with concurrent.futures.ThreadPoolExecutor(JOBS) as pool:
                results = list(pool.map(one, range(1, runs + 1)))
            for seed, ident, code in results:
                level, p = lack_of_fit_figures(ident)
                extremes = [max(extremes[0], level), min(extremes[1], p)]
                f = flags(ident, code)
                for r in RULES:
                    counts[r] += f[r]
                counts["any"] += any(f.values())
                if any(f.values()):
                    print(f"    flagged: {case} seed {seed}: {[r for r in RULES if f[r]]}",
                          flush=True)
            row(case, runs, counts, extremes)
            for r in counts:
                total[r] += counts[r]
            total_runs += runs
    row("ALL CLEAN RUNS", total_runs, total)


def detections():
    print("\nDETECTIONS")
    n = max(N // 10, 5)
    # A pedestal on its own sub-base: untrusted (lack of fit) at that bearing
    # only. Three machines: a machine file with the base element under `mid`,
    # the simulator's pedestal_sub_base effect, the ROSS reference machine d.
    subs = [
        ("three-bearing-sub-base.toml", SUB, [], "mid"),
        ("three-bearing + effect sub_base:drive", THREE,
         ["--effect", "pedestal_sub_base:drive"], "drive"),
        ("ross machine-d (sub_base on B1)", ROSS_D, [], "B1"),
    ]
    for name, machine, extra, bearing in subs:
        for kind in ("digits 3", "digits 12", "noise 1 %"):
            runs = n if kind.startswith("noise") else 1
            hit = wrong = 0
            for seed in range(1, runs + 1):
                out = os.path.join(W, "sub")
                if kind.startswith("digits"):
                    sim(machine, out, "--digits", kind.split()[1], *extra)
                else:
                    sim(machine, out, "--noise", "0.01", "--seed", str(seed), *extra)
                base = os.path.join(out, "base.csv")
                if os.path.exists(base):
                    os.remove(base)
                ident, _ = identify(out)
                for p in ident["pedestals"]:
                    untrusted = not p["trusted"]
                    if p["bearing"] == bearing:
                        hit += untrusted
                    else:
                        wrong += untrusted
            print(f"  sub-base {name:40s} {kind:9s}: {bearing} untrusted in {hit}/{runs} runs;"
                  f" other pedestals untrusted {wrong} times", flush=True)
    # Keyphasor flips: three speeds of one bearing negated; listed exactly.
    exact = os.path.join(W, "exact")
    sim(THREE, exact, "--digits", "12")
    hit = named = runs = 0
    for seed in range(1, n + 1):
        rng = random.Random(seed)
        speeds = sorted(rng.sample([5 + 2.5 * i for i in range(8, 76)], 3))
        out = os.path.join(W, "flip")
        data(exact, out, "--noise", "0.01", "--seed", str(seed),
             "--flip", "mid:" + ",".join(f"{s:g}" for s in speeds))
        ident, _ = identify(out)
        exact_list = True
        for p in ident["pedestals"]:
            got = listed(ident, p["bearing"])
            if p["bearing"] == "mid":
                exact_list &= sorted(got) == speeds
                named += any(w["kind"] == "keyphasor_flip" for w in p["warnings"])
            else:
                exact_list &= not got
        hit += exact_list
        runs += 1
    print(f"  keyphasor flip, 3 speeds of `mid`, 1 % noise: listed exactly in {hit}/{runs} runs,"
          f" keyphasor_flip named in {named}/{runs}", flush=True)
    # One bad reading (every channel of `drive` off by 20x its noise, random
    # phase) at a random speed: listed exactly, nothing else listed.
    hit = runs = 0
    for seed in range(1, n + 1):
        rng = random.Random(1000 + seed)
        s = rng.choice([5 + 2.5 * i for i in range(4, 76)])
        out = os.path.join(W, "outlier")
        data(exact, out, "--noise", "0.01", "--seed", str(seed),
             "--outlier", f"drive:{s:g}:0.2")
        ident, _ = identify(out)
        ok = listed(ident, "drive") == [s]
        ok &= all(not listed(ident, p["bearing"]) for p in ident["pedestals"]
                  if p["bearing"] != "drive")
        hit += ok
        runs += 1
    print(f"  one outlier speed of `drive` (0.2 x channel RMS), 1 % noise: listed exactly in"
          f" {hit}/{runs} runs", flush=True)
    # Unit and convention mistakes, absurd magnitudes.
    for label, args, test in [
        ("ped in um, rel in m", ["--ped-scale", "1e6"],
         lambda p: any(w["kind"] == "implausible" and "ped in µm" in w["message"]
                       for w in p["warnings"])),
        ("ped phasors conjugated", ["--ped-conjugate"],
         lambda p: p.get("suspected_convention_error") == "ped_conjugated"),
        ("ped x 1e-100 (absurd)", ["--ped-scale", "1e-100"], lambda p: not p["trusted"]),
    ]:
        hit = tot = 0
        for mname, machine in (("paper", PAPER), ("three-bearing", THREE)):
            for digits in ("3", "12"):
                exact = os.path.join(W, "exact")
                sim(machine, exact, "--digits", "12")
                out = os.path.join(W, "fault")
                data(exact, out, *args, "--digits", digits)
                ident, code = identify(out)
                for p in ident["pedestals"]:
                    tot += 1
                    hit += bool(test(p))
        print(f"  {label:28s}: named at {hit}/{tot} pedestals (2 machines x digits 3, 12)",
              flush=True)


t0 = time.time()
if not ONLY:
    detections()
false_alarms()
print(f"\n({time.time() - t0:.0f} s)")
subprocess.run(["rm", "-rf", W])
