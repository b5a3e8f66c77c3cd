#!/usr/bin/env python3
"""Monte-Carlo of identify's trust rules (run by scripts/bench-trust.sh).

False alarms: clean runs (the paper's undamped machine, whose pedestal
damping is truly zero, and a three-bearing machine with cross-coupled
tabulated bearings) at digits 2/3/12, white noise of several levels,
heteroscedastic noise and noise columns (scripts/bench_common.py). A run is
a false alarm for a rule when any of its pedestals carries that rule's
warning (lack_of_fit, physically_impossible, suspected_convention_error,
implausible), lists an outlier speed (outlier_speeds_hz: robust fit or
keyphasor flip), or `plinth identify` exits 2.

The noise level measured without the model (the scatter source) against
the true sd of the noise added, per bearing and channel, on clean runs of
resonant machines.

Detections: the faults each rule is for: a pedestal on its own sub-base
(three machines), three speeds with one bearing's phasors flipped by 180°,
one bad reading, pedestal pick-ups in um or mm against probes in m (a
refusal by the reader's bounds counts as named when it names the mix-up
between channels), only the pedestal phasors conjugated, absurd magnitudes.

Test data come from `plinth simulate` (the simulator's elements, its
`pedestal_sub_base` effect and machine-file `sub_base`) and
scripts/trust_data.py (noise, columns, faults), not from the estimator.

Each row prints the flagged % per rule and, for the run-level verdict
("any"), the one-sided 95 % upper bound of the false-alarm rate
(Clopper-Pearson). Runs go in parallel over $BENCH_JOBS workers (default:
the CPU count).

With --ross RUNS_DIR (run it with the ROSS 2.3.0 python): the false alarms
per rule on the clean cases (`clean-*`) of the five unseen machines of
scripts/ross_unseen.py instead (made by ROSS, not by Plinth's simulator;
RUNS_DIR/MACHINE/CASE-SEED, missing ones made first, kept for a rerun),
RUNS_PER_CASE seeds each; CASE_FILTER is then a regular expression searched
in "MACHINE CASE" (e.g. "clean-(w1|h1|p2|n1|n3|vel)": the noisy cases).

With --runs PARENT: the false alarms per rule over every run directory
(holding measurements.csv) directly under PARENT, as one row, e.g. clean
null draws of an extracted recording (scripts/ross_recording.py --null);
RUNS_PER_CASE and CASE_FILTER are then ignored.

usage: bench_trust.py [--first-seed S] [--ross RUNS_DIR | --runs PARENT]
                      PLINTH_BINARY [RUNS_PER_CASE] [CASE_FILTER]
  --first-seed S: every case's runs (false alarms and detections) use seeds
  S, S+1, ... instead of 1, 2, ... (default 1: old figures reproduce).
  CASE_FILTER: run only the false-alarm cases whose name contains it (and
  no detections), e.g. "paper-undamped hetero".
"""
import csv
import json
import math
import os
import random
import re
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402

CHANNELS = ["rel_y", "rel_z", "ped_y", "ped_z"]
# ROSS reference machine c: pedestals on two flexible bases (base.csv).
ROSS_C = os.path.join(bc.ROOT, "tests", "reference", "ross", "machine-c.toml")
RULES = ["lack_of_fit", "physically_impossible", "suspected_convention_error",
         "implausible", "outliers_listed", "exit_2"]


def flags(ident, code):
    """Which of RULES fired on one run."""
    got = {r: False for r in RULES}
    for p in ident["pedestals"]:
        for w in p["warnings"]:
            if w["kind"] in got:
                got[w["kind"]] = True
        if bc.listed(ident, p["bearing"]):
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


def undetermined(ident):
    """1 when some pedestal of the run is `undetermined` (untrusted, exit 0:
    a value the data do not determine, no fault claimed), else 0; counted
    apart from RULES and "any"."""
    return int(any(w["kind"] == "undetermined" for p in ident["pedestals"] for w in p["warnings"]))


def tally(results, label):
    """Counts per rule (and "any", "undetermined") over `results`, an
    iterable of (name, identify JSON, exit code); prints each flagged run as
    "flagged: LABEL NAME: [rules]"."""
    counts = {r: 0 for r in RULES + ["any", "undetermined"]}
    for name, ident, code in results:
        f = flags(ident, code)
        for r in RULES:
            counts[r] += f[r]
        counts["any"] += any(f.values())
        counts["undetermined"] += undetermined(ident)
        if any(f.values()):
            print(f"    flagged: {label}{name}: {[r for r in RULES if f[r]]}", flush=True)
    return counts


def row(case, runs, counts, extremes=None):
    if counts.get("undetermined"):
        print(f"    runs with a pedestal `undetermined` (not a false alarm: no fault claimed):"
              f" {counts['undetermined']}/{runs}", flush=True)
    cells = "  ".join(f"{100.0 * counts[r] / max(runs, 1):6.2f}" for r in RULES)
    anyc = counts["any"]
    ext = f"  {extremes[0]:8.3f} {extremes[1]:8.4f}" if extremes else ""
    print(f"{case:34s} {runs:5d}  {cells}  {100.0 * anyc / max(runs, 1):6.2f}"
          f" {100.0 * bc.upper95(anyc, runs):6.2f}{ext}", flush=True)


def header(title):
    print(f"\n{title}")
    print(f"{'case':34s} {'runs':>5s}  " + "  ".join(f"{r[:6]:>6s}" for r in RULES)
          + "     any  ≤95%up  maxlevel  min p")
    print(f"{'':34s} {'':5s}  " + "  ".join(f"{'%':>6s}" for _ in RULES))


def false_alarms(plinth, n, only, first=1):
    header("FALSE ALARMS per run on clean data (flagged %, by rule)")
    total = {r: 0 for r in RULES + ["any", "undetermined"]}
    total_runs = 0
    for case, runs, results in bc.clean_identifications(plinth, n, only, first):
        results = list(results)
        extremes = [0.0, 1.0]
        for _, ident, _ in results:
            level, p = lack_of_fit_figures(ident)
            extremes = [max(extremes[0], level), min(extremes[1], p)]
        counts = tally(results, f"{case} seed ")
        row(case, runs, counts, extremes)
        for r in counts:
            total[r] += counts[r]
        total_runs += runs
    row("ALL CLEAN RUNS", total_runs, total)


ROSS_MACHINES = ("unseen-four", "unseen-overhung", "unseen-train", "unseen-flex", "unseen-five")


def ross_false_alarms(plinth, n, only, first, runs_dir):
    """`false_alarms` on ROSS-made clean runs: every `clean-*` case of the
    five unseen machines whose "MACHINE CASE" contains `only`, seeds
    first..first+n-1, made by scripts/ross_unseen.py (one process a
    machine, ROSS's responses cached) where RUNS_DIR lacks them. `only`
    is a regular expression searched in "MACHINE CASE"."""
    header("FALSE ALARMS per run on clean ROSS runs (flagged %, by rule)")
    total = {r: 0 for r in RULES + ["any", "undetermined"]}
    total_runs = 0
    seeds = range(first, first + n)
    for machine in ROSS_MACHINES:
        script = os.path.join(bc.ROOT, "scripts", "ross_unseen.py")
        listing = subprocess.run([sys.executable, script, "--machine", machine, "--cases"],
                                 check=True, capture_output=True, text=True).stdout.split()
        cases = [c for c in listing if c.startswith("clean-") and re.search(only, f"{machine} {c}")]
        if not cases:
            continue
        where = os.path.join(runs_dir, machine)
        missing = [c for c in cases
                   if any(not os.path.isdir(os.path.join(where, f"{c}-{s}")) for s in seeds)]
        if missing:
            subprocess.run([sys.executable, script, "--machine", machine, where, ",".join(missing),
                            *[str(s) for s in seeds]], check=True, stdout=subprocess.DEVNULL)
        for case in cases:
            if not os.path.exists(os.path.join(where, f"{case}-{first}", "measurements.csv")):
                print(f"  {machine} {case}: not a run directory (a field case to import), left out",
                      flush=True)
                continue

            def one(seed, case=case, where=where):
                return (seed, *plinth.identify(os.path.join(where, f"{case}-{seed}")))

            counts = tally(bc.parallel(one, seeds), f"{machine} {case} seed ")
            row(f"{machine} {case}", n, counts)
            for r in counts:
                total[r] += counts[r]
            total_runs += n
    row("ALL CLEAN ROSS RUNS", total_runs, total)


def stored_false_alarms(plinth, parent):
    """`false_alarms` over the run directories under `parent` (module docs)."""
    header(f"FALSE ALARMS per run on the clean runs under {parent} (flagged %, by rule)")
    runs = sorted(d for d in os.listdir(parent)
                  if os.path.exists(os.path.join(parent, d, "measurements.csv")))
    results = bc.parallel(lambda d: plinth.identify(os.path.join(parent, d)), runs)
    counts = tally(((name, *r) for name, r in zip(runs, results)), "")
    row(os.path.basename(os.path.normpath(parent)), len(runs), counts)


def sub_base(plinth, n, first=1):
    """A pedestal on its own sub-base: untrusted (lack of fit) at that bearing
    only. Three machines: a machine file with the base element under `mid`,
    the simulator's pedestal_sub_base effect, the ROSS reference machine d."""
    subs = [
        ("three-bearing-sub-base.toml", bc.SUB, [], "mid"),
        ("three-bearing + effect sub_base:drive", bc.THREE,
         ["--effect", "pedestal_sub_base:drive"], "drive"),
        ("ross machine-d (sub_base on B1)", bc.ROSS_D, [], "B1"),
    ]
    for name, machine, extra, bearing in subs:
        for kind in ("digits 3", "digits 12", "noise 1 %"):
            runs = n if kind.startswith("noise") else 1

            def one(seed, kind=kind, machine=machine, extra=extra, bearing=bearing):
                out = plinth.path(f"sub-{seed}")
                if kind.startswith("digits"):
                    plinth.sim(machine, out, "--digits", kind.split()[1], *extra)
                else:
                    plinth.sim(machine, out, "--noise", "0.01", "--seed", str(seed), *extra)
                base = os.path.join(out, "base.csv")
                if os.path.exists(base):
                    os.remove(base)
                ident, _ = plinth.identify(out)
                subprocess.run(["rm", "-rf", out], check=True)
                hit = wrong = 0
                for p in ident["pedestals"]:
                    untrusted = not p["trusted"]
                    if p["bearing"] == bearing:
                        hit += untrusted
                    else:
                        wrong += untrusted
                return seed, hit, wrong

            results = bc.parallel(one, range(first, first + runs))
            hit = sum(r[1] for r in results)
            wrong = sum(r[2] for r in results)
            missed = [r[0] for r in results if not r[1]]
            print(f"  sub-base {name:40s} {kind:9s}: {bearing} untrusted in {hit}/{runs} runs;"
                  f" other pedestals untrusted {wrong} times"
                  + (f" (missed seeds {missed})" if missed and runs > 1 else ""), flush=True)


def flips_and_outliers(plinth, n, first=1):
    """Keyphasor flips (three speeds of one bearing negated) and one bad
    reading: listed exactly."""
    exact = plinth.path("exact-three")
    plinth.sim(bc.THREE, exact, "--digits", "12")

    def flip(seed):
        rng = random.Random(seed)
        speeds = sorted(rng.sample(bc.GRID[8:76], 3))
        out = plinth.path(f"flip-{seed}")
        bc.data(exact, out, "--noise", "0.01", "--seed", str(seed),
                "--flip", "mid:" + ",".join(f"{s:g}" for s in speeds))
        ident, _ = plinth.identify(out)
        subprocess.run(["rm", "-rf", out], check=True)
        exact_list = True
        named = False
        for p in ident["pedestals"]:
            got = bc.listed(ident, p["bearing"])
            if p["bearing"] == "mid":
                exact_list &= sorted(got) == speeds
                named = any(w["kind"] == "keyphasor_flip" for w in p["warnings"])
            else:
                exact_list &= not got
        return exact_list, named

    results = bc.parallel(flip, range(first, first + n))
    print(f"  keyphasor flip, 3 speeds of `mid`, 1 % noise: listed exactly in"
          f" {sum(r[0] for r in results)}/{n} runs, keyphasor_flip named in"
          f" {sum(r[1] for r in results)}/{n}", flush=True)

    # One bad reading (every channel of `drive` off by 0.2 x its RMS, random
    # phase) at a random speed: listed exactly, nothing else listed.
    def outlier(seed):
        rng = random.Random(1000 + seed)
        s = rng.choice(bc.GRID[4:76])
        out = plinth.path(f"outlier-{seed}")
        bc.data(exact, out, "--noise", "0.01", "--seed", str(seed),
                "--outlier", f"drive:{s:g}:0.2")
        ident, _ = plinth.identify(out)
        subprocess.run(["rm", "-rf", out], check=True)
        ok = bc.listed(ident, "drive") == [s]
        ok &= all(not bc.listed(ident, p["bearing"]) for p in ident["pedestals"]
                  if p["bearing"] != "drive")
        return ok

    hits = sum(bc.parallel(outlier, range(first, first + n)))
    print(f"  one outlier speed of `drive` (0.2 x channel RMS), 1 % noise: listed exactly in"
          f" {hits}/{n} runs", flush=True)


def identify_or_refusal(plinth, run):
    """(`plinth identify RUN --json` parsed or None, stderr): exit 1 (identify
    refused the data, e.g. a phasor beyond any machine's) returns None with
    the refusal's message; any exit but 0, 1, 2 raises."""
    p = subprocess.run([plinth.binary, "identify", run, "--json"], capture_output=True,
                       text=True)
    if p.returncode == 1:
        return None, p.stderr
    if p.returncode not in (0, 2):
        raise RuntimeError(f"identify {run}: exit {p.returncode}: {p.stderr}")
    return json.loads(p.stdout), p.stderr


def conventions(plinth):
    """Unit and convention mistakes, absurd magnitudes: named at every pedestal.
    A unit mix-up may also be refused by the reader's bounds (a phasor beyond
    any machine's, host/src/rundir/bounds.rs): that run counts as named at
    every pedestal only when the refusal names the mix-up between channels
    (`ped written in <unit>`, the unit first), else as missed."""
    def unit(u):
        return (lambda p: any(w["kind"] == "implausible" and f"ped in {u}" in w["message"]
                              for w in p["warnings"]),
                lambda err: f"ped written in {u}" in err)
    for label, args, test, refusal in [
        ("ped in um, rel in m", ["--ped-scale", "1e6"], *unit("µm")),
        ("ped in mm, rel in m", ["--ped-scale", "1e3"], *unit("mm")),
        ("ped phasors conjugated", ["--ped-conjugate"],
         lambda p: p.get("suspected_convention_error") == "ped_conjugated", None),
        ("ped x 1e-100 (absurd)", ["--ped-scale", "1e-100"], lambda p: not p["trusted"], None),
    ]:
        hit = tot = refused = named_refusals = 0
        for _, machine in (("paper", bc.PAPER), ("three-bearing", bc.THREE)):
            for digits in ("3", "12"):
                exact = plinth.path("exact")
                plinth.sim(machine, exact, "--digits", "12")
                out = plinth.path("fault")
                bc.data(exact, out, *args, "--digits", digits)
                ident, err = identify_or_refusal(plinth, out)
                if ident is None:
                    refused += 1
                    with open(os.path.join(out, "measurements.csv")) as fh:
                        pedestals = len({r["bearing"] for r in csv.DictReader(fh)})
                    tot += pedestals
                    if refusal is not None and refusal(err):
                        hit += pedestals
                        named_refusals += 1
                    continue
                for p in ident["pedestals"]:
                    tot += 1
                    hit += bool(test(p))
        print(f"  {label:28s}: named at {hit}/{tot} pedestals (2 machines x digits 3, 12)"
              + (f"; {refused} of the 4 runs refused by the reader's bounds, {named_refusals}"
                 " of them naming the mix-up" if refused else ""),
              flush=True)


def channel_rms(run):
    """RMS over speed [m] of each (bearing, channel) of RUN's measurements.csv:
    what trust_data.py's --noise F is a fraction of."""
    acc = {}
    with open(os.path.join(run, "measurements.csv")) as fh:
        for r in csv.DictReader(fh):
            for c in CHANNELS:
                z = complex(float(r[c + "_re"]), float(r[c + "_im"]))
                acc.setdefault((r["bearing"], c), []).append(abs(z) ** 2)
    return {k: math.sqrt(sum(v) / len(v)) for k, v in acc.items()}


def scatter_level(plinth, n, first=1):
    """The noise level identify measures without the model (the `scatter`
    source, before the fit's χ²/dof rescaling: sd / sqrt(variance_scale))
    against the true sd of the white noise trust_data.py added (1 % of each
    channel's RMS), per bearing and channel, on clean runs of resonant
    machines (the pedestals of ROSS machine-c on its bases, base.csv kept)
    and on the sub-base machines (their sub-base bearing too)."""
    machines = [("paper-undamped", bc.PAPER, False), ("three-bearing", bc.THREE, False),
                ("three-bearing-sub-base", bc.SUB, False), ("ross machine-c", ROSS_C, True),
                ("ross machine-d", bc.ROSS_D, False)]
    print("  scatter level / true noise sd at 1 % white noise (median over runs; max):")
    for name, machine, keep in machines:
        exact = plinth.path("exact-level")
        plinth.sim(machine, exact, "--digits", "12")
        rms = channel_rms(exact)

        def one(seed, exact=exact, keep=keep):
            out = plinth.path(f"level-{seed}")
            bc.data(exact, out, "--noise", "0.01", "--seed", str(seed),
                    *(["--keep-base"] if keep else []))
            ident, _ = plinth.identify(out)
            subprocess.run(["rm", "-rf", out], check=True)
            return {b: [nr["sd"][c] / math.sqrt(nr["variance_scale"]) / (0.01 * rms[(b, c)])
                        for c in CHANNELS]
                    for b, nr in ident["noise"].items() if nr["source"] == "scatter"}

        results = bc.parallel(one, range(first, first + n))
        for b in sorted({b for r in results for b in r}):
            cells = []
            for i, c in enumerate(CHANNELS):
                v = [r[b][i] for r in results if b in r]
                cells.append(f"{c} {statistics.median(v):5.2f} ({max(v):5.2f})")
            print(f"    {name:24s} {b:9s} " + "  ".join(cells), flush=True)


def detections(plinth, n, first=1):
    print("\nDETECTIONS")
    n = max(n // 10, 5)
    scatter_level(plinth, n, first)
    sub_base(plinth, n, first)
    flips_and_outliers(plinth, n, first)
    conventions(plinth)


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    dirs = {}
    for flag in ("--ross", "--runs"):
        if flag in argv:
            i = argv.index(flag)
            if i + 1 >= len(argv):
                raise SystemExit(f"{flag} needs a directory")
            dirs[flag] = argv[i + 1]
            del argv[i:i + 2]
    binary, n, only, first = bc.arguments(argv, first_seed=True)
    plinth = bc.Plinth(binary, "bench-trust-")
    t0 = time.time()
    try:
        if "--ross" in dirs:
            ross_false_alarms(plinth, n, only, first, dirs["--ross"])
            return
        if "--runs" in dirs:
            stored_false_alarms(plinth, dirs["--runs"])
            return
        if not only:
            detections(plinth, n, first)
        false_alarms(plinth, n, only, first)
    finally:
        print(f"\n({time.time() - t0:.0f} s)")
        plinth.close()


if __name__ == "__main__":
    main()
