#!/usr/bin/env python3
"""The support-mode rule's false-alarm rate and power at candidate rates
(docs/trust-support-mode.md, session 35).

identify's support-mode test (host/src/estimate/lack_of_fit/support.rs) is
made only at bearings with noise columns; its p-value is in
`identify --json` `noise.<b>.lack_of_fit.support_mode.p_value`, and the
rule (host/src/identify/trust.rs) untrusts a bearing whose p is below
SUPPORT_FALSE_ALARM/U, U the bearings tested in the run. One run of
identify per dataset therefore gives the rule's verdict at every candidate
rate R in RATES: a run is flagged by the rule at R when any bearing has
p < R/U.

"any rule" at R is the run flagged by identify as bench_trust.py counts it
(any pedestal untrusted, a bench_trust rule fired, exit 2) OR by the
support rule at R: exact for every R at or above the binary's own
SUPPORT_FALSE_ALARM (the other rules do not depend on it), so run it with
a binary whose rate is the smallest candidate's (main's 0.001).

Parts (any of them; default all):
  trust   scripts/bench_trust.py's clean cases (bench_common.clean_identifications),
          with and without noise columns, RUNS runs each (hetero: at least 200);
          trust=TEXT: only the cases whose name contains TEXT.
  unseen  the four unseen machines' clean noisy cases from ROSS 2.3.0
          (scripts/ross_unseen.py, in-process), with columns (clean-w1c,
          clean-h1c, clean-p2c, clean-n1c) and without (the same without c),
          seeds 1..RUNS.
  power   the sub-base case of the four unseen machines (ROSS), seeds
          1..RUNS, at the bearing under which the sub-base is; and the
          three sub-base machines of bench_trust.py at 1 % noise with noise
          columns (trust_data.py --columns: bench_trust's own sub-base rows
          have no columns, so the support test is not made there), seeds
          1..RUNS.
unseen=REGEX: only the rows "MACHINE CASE" REGEX matches (e.g. "c$": the
cases with columns); power=TEXT: only the unseen machines whose name
contains TEXT (power=bench: only bench_trust's sub-base machines).

Each row: runs, bearing tests, then per rate the runs flagged by the
support rule (false alarms; detections at the sub-base bearing for power
rows) and, for clean rows, by any rule; the one-sided 95 % upper bound
(Clopper-Pearson) of the pooled clean rates is printed last.

diagnose: on the unseen machines' clean runs whose support p lies below
the largest candidate's limit (the only runs whose diagnosis the rate can
change: diagnose reads the rate only through identify::trust::support_limit),
`plinth diagnose RUN --machine FILE --json` is run with the binary and its
verdict listed ("diagnose untrusted k/n" per row): run the script with
main's binary and with a binary at another rate for diagnose at both.

The claim (session 36): at the adopted rate ADOPTED, the support rule's
clean false-alarm rate per run is within the issue's BUDGET on every clean
row and pooled. Printed last; the script exits 1 when a row's or the
pooled rate at ADOPTED exceeds BUDGET (refuted), and says "not established"
when the pooled 95 % upper bound does (too few runs).

usage: bench_support_rate.py PLINTH_BINARY RUNS [PART ...]
Runs go over $BENCH_JOBS workers (default: the CPU count).
"""
import json
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_common as bc  # noqa: E402
import bench_trust as bt  # noqa: E402

# Candidate per-run rates of the support-mode rule [-].
RATES = (0.001, 0.002, 0.003, 0.005, 0.01)
# The rate adopted for SUPPORT_FALSE_ALARM (host/src/identify/trust.rs) and
# the clean budget per run and rule [-].
ADOPTED = 0.005
BUDGET = 0.01
# The unseen machines: (ross_unseen.py name, clean noisy case without
# columns, sub-base case's bearing).
UNSEEN = (("unseen-four", "clean-w1", "B3"), ("unseen-overhung", "clean-h1", "B1"),
          ("unseen-train", "clean-p2", "B2"), ("unseen-flex", "clean-n1", "B1"))


def support_ps(ident):
    """{bearing: support-mode p-value} over the bearings where it was made."""
    out = {}
    for b, n in ident["noise"].items():
        t = (n.get("lack_of_fit") or {}).get("support_mode")
        if t:
            out[b] = t["p_value"]
    return out


def flagged_at(ps, rate):
    """The bearings the support rule flags at per-run rate `rate`."""
    return {b for b, p in ps.items() if p < rate / max(len(ps), 1)}


def record(ident, code):
    """(support p-values, flagged by identify as it is) of one run."""
    if ident is None:
        return {}, code == 2
    main = any(bt.flags(ident, code).values()) or any(not p["trusted"]
                                                      for p in ident["pedestals"])
    return support_ps(ident), main


class Tally:
    """Counts of one row."""

    def __init__(self, name):
        self.name, self.runs, self.tests = name, 0, 0
        self.support = [0] * len(RATES)
        self.any = [0] * len(RATES)
        self.diagnosed = []
        self.notes = []

    def add(self, label, ps, main, target=None):
        """Adds one run: `target` None counts a false alarm at any bearing,
        else a detection at `target`."""
        self.runs += 1
        self.tests += len(ps)
        for i, r in enumerate(RATES):
            f = flagged_at(ps, r)
            hit = (target in f) if target else bool(f)
            self.support[i] += hit
            self.any[i] += main or bool(f)
            if hit and target is None:
                self.notes.append(f"{label} at {r}: {sorted(f)}")
        if target is not None and target not in flagged_at(ps, RATES[-1]):
            self.notes.append(f"{label}: {target} p = {ps.get(target, float('nan')):.2e}"
                              f" (missed at every rate)")

    def row(self, clean=True):
        cells = " ".join(f"{s:5d}" for s in self.support)
        anys = ("  any " + " ".join(f"{a:5d}" for a in self.any)) if clean else ""
        print(f"{self.name:44s} {self.runs:5d} {self.tests:6d}  {cells}{anys}", flush=True)
        if self.diagnosed:
            bad = [label for label, trusted in self.diagnosed if not trusted]
            print(f"      diagnose untrusted {len(bad)}/{len(self.diagnosed)} of the runs "
                  f"the rate can change: {bad}", flush=True)
        for n in self.notes[:12]:
            print(f"      {n}", flush=True)


def header(title, clean=True):
    rates = " ".join(f"{r:5g}" for r in RATES)
    print(f"\n{title}\n{'case':44s} {'runs':>5s} {'tests':>6s}  {rates}"
          + (f"  any {rates}" if clean else ""), flush=True)


def trust_part(plinth, n, pooled, only):
    header("bench_trust clean cases: runs flagged by the support rule per rate; by any rule")
    for case, _, results in bc.clean_identifications(plinth, n, only):
        t = Tally(case)
        for seed, ident, code in results:
            t.add(f"seed {seed}", *record(ident, code))
        t.row()
        pooled.append(t)


def diagnose_trusted(plinth, run, machine_file):
    """`plinth diagnose RUN --machine FILE --json`'s `trusted` (False when it
    exits with an error)."""
    p = subprocess.run([plinth.binary, "diagnose", run, "--machine", machine_file, "--json"],
                       capture_output=True, text=True)
    if p.returncode not in (0, 2):
        return False
    return bool(json.loads(p.stdout)["trusted"])


def ross_runs(machine, case, seeds, plinth, diagnose=False):
    """[(seed, identify JSON, exit code, diagnose's trusted or None)] of ROSS
    runs CASE-SEED of `machine`, made in-process (ROSS's response cached per
    grid) and removed; with `diagnose`, diagnosed where the support rule
    flags the run at the largest candidate rate (module docs)."""
    import ross_unseen as ru

    def one(seed):
        out = plinth.path(f"{machine}-{case}-{seed}")
        ru.make(out, case, seed, machine)
        ident, code = plinth.identify(out, refusal_ok=True)
        trusted = None
        if diagnose and ident is not None and flagged_at(support_ps(ident), RATES[-1]):
            trusted = diagnose_trusted(plinth, out, ru.machine_file(machine))
        subprocess.run(["rm", "-rf", out], check=True)
        return seed, ident, code, trusted
    # ROSS first on one seed (fills the cache), then the rest in parallel.
    first = [one(seeds[0])]
    return first + bc.parallel(one, seeds[1:])


def unseen_part(plinth, n, pooled, only):
    header("unseen machines' clean cases (ROSS): runs flagged by the support rule; by any rule")
    for machine, case, _ in UNSEEN:
        for c in (case + "c", case):
            if not re.search(only, f"{machine} {c}"):
                continue
            t = Tally(f"{machine} {c}")
            for seed, ident, code, trusted in ross_runs(machine, c, list(range(1, n + 1)),
                                                        plinth, diagnose=True):
                t.add(f"seed {seed}", *record(ident, code))
                if trusted is not None:
                    t.diagnosed.append((f"seed {seed}", trusted))
            t.row()
            pooled.append(t)


def power_part(plinth, n, only):
    header("POWER: runs whose sub-base bearing the support rule flags, per rate", clean=False)
    for machine, _, bearing in (u for u in UNSEEN if only in u[0]):
        t = Tally(f"{machine} sub-base")
        for seed, ident, code, _ in ross_runs(machine, "sub-base", list(range(1, n + 1)),
                                              plinth):
            t.add(f"seed {seed}", *record(ident, code), bearing)
        t.row(clean=False)
    subs = [("three-bearing-sub-base.toml", bc.SUB, [], "mid"),
            ("three-bearing + effect sub_base:drive", bc.THREE,
             ["--effect", "pedestal_sub_base:drive"], "drive"),
            ("ross machine-d (sub_base on B1)", bc.ROSS_D, [], "B1")]
    for name, machine, extra, bearing in (s for s in subs if only in "bench"):
        exact = plinth.path("exact-sub")
        plinth.sim(machine, exact, "--digits", "12", *extra)
        base = os.path.join(exact, "base.csv")
        if os.path.exists(base):
            os.remove(base)

        def one(seed, exact=exact):
            out = plinth.path(f"sub-{seed}")
            bc.data(exact, out, "--noise", "0.01", "--columns", "--seed", str(seed))
            ident, code = plinth.identify(out)
            subprocess.run(["rm", "-rf", out], check=True)
            return seed, ident, code

        t = Tally(f"{name}, 1 % + columns")
        for seed, ident, code in bc.parallel(one, range(1, n + 1)):
            ps, main = record(ident, code)
            t.add(f"seed {seed}", ps, main, bearing)
        t.row(clean=False)


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    binary, n, parts = args[0], int(args[1]), args[2:] or ["trust", "unseen", "power"]
    plinth = bc.Plinth(binary, "bench-support-")
    t0 = time.time()
    pooled, refuted = [], False
    try:
        for part in parts:
            if part.split("=")[0] == "trust":
                trust_part(plinth, n, pooled, part.partition("=")[2])
        for part in parts:
            if part.split("=")[0] == "unseen":
                unseen_part(plinth, n, pooled, part.partition("=")[2])
        if pooled:
            runs = sum(t.runs for t in pooled)
            print(f"\nALL CLEAN RUNS ({runs}): support rule / any rule per rate, "
                  "with the one-sided 95 % upper bound")
            for i, r in enumerate(RATES):
                s = sum(t.support[i] for t in pooled)
                a = sum(t.any[i] for t in pooled)
                print(f"  rate {r:5g}: support {s}/{runs} = {100 * s / runs:.2f} % "
                      f"(≤ {100 * bc.upper95(s, runs):.2f} %); any {a}/{runs} = "
                      f"{100 * a / runs:.2f} % (≤ {100 * bc.upper95(a, runs):.2f} %)", flush=True)
            refuted = claim(pooled)
        for part in parts:
            if part.split("=")[0] == "power":
                power_part(plinth, n, part.partition("=")[2])
    finally:
        print(f"\n({time.time() - t0:.0f} s)")
        plinth.close()
    if pooled and refuted:
        sys.exit(1)


def claim(pooled):
    """Prints the claim's check at ADOPTED (module docs); True when refuted."""
    i = RATES.index(ADOPTED)
    runs = sum(t.runs for t in pooled)
    flagged = sum(t.support[i] for t in pooled)
    over = [t.name for t in pooled if t.runs and t.support[i] > BUDGET * t.runs]
    bound = bc.upper95(flagged, runs)
    if over or flagged > BUDGET * runs:
        verdict = f"REFUTED (over {BUDGET}: {over or 'pooled'})"
    elif bound > BUDGET:
        verdict = f"not established (95 % bound {100 * bound:.2f} % over {100 * BUDGET:g} %: more runs)"
    else:
        verdict = f"holds (every row at most {100 * BUDGET:g} %, pooled ≤ {100 * bound:.2f} %)"
    print(f"CLAIM: the support rule at {ADOPTED} per run flags {flagged}/{runs} clean runs: "
          f"{verdict}", flush=True)
    return verdict.startswith("REFUTED")


if __name__ == "__main__":
    main()
