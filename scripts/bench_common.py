#!/usr/bin/env python3
"""What the Monte-Carlo benches of identify's trust rules share
(scripts/bench_trust.py; scripts/bench_flips.py may use it too): the
machines, the clean cases, running `plinth simulate`, scripts/trust_data.py
and `plinth identify --json`, reading what identify lists, the speed grids
of the digit cases, and the Clopper-Pearson bound of a rate.

Test data come from `plinth simulate` (the simulator's elements and
effects) and scripts/trust_data.py (noise, columns, faults), never from the
estimator.
"""
import concurrent.futures
import json
import math
import os
import random
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "scripts", "trust_data.py")
PAPER = os.path.join(ROOT, "examples", "feng-hahn-1997.toml")
THREE = os.path.join(ROOT, "tests", "machines", "three-bearing-tabulated.toml")
SUB = os.path.join(ROOT, "tests", "machines", "three-bearing-sub-base.toml")
ROSS_D = os.path.join(ROOT, "tests", "reference", "ross", "machine-d.toml")
# The clean machines: the undamped paper machine (pedestal damping truly
# zero) and a three-bearing machine with cross-coupled tabulated bearings.
CLEAN_MACHINES = (("paper-undamped", PAPER), ("three-bearing", THREE))
# The run-down of every case but the digit ones [Hz]: first:last:step.
SPEEDS = "5:200:2.5"
# Its speeds [Hz].
GRID = [5 + 2.5 * i for i in range(79)]


def arguments(argv=None, first_seed=False):
    """(PLINTH_BINARY, RUNS_PER_CASE (default 100), CASE_FILTER (default ""))
    from the command line of a bench; with `first_seed`, also FIRST_SEED
    (default 1) from `[--first-seed S] PLINTH_BINARY ...`: each case's runs
    then use seeds FIRST_SEED..FIRST_SEED+runs-1 (default 1..runs, as before
    the flag: old figures reproduce; a later first seed gives fresh runs
    nobody has looked at). A bench that does not take the flag refuses it."""
    argv = list(sys.argv[1:] if argv is None else argv)
    first = 1
    if "--first-seed" in argv:
        if not first_seed:
            raise SystemExit("this bench does not take --first-seed")
        i = argv.index("--first-seed")
        if i + 1 >= len(argv):
            raise SystemExit("--first-seed needs a value")
        first = int(argv[i + 1])
        del argv[i:i + 2]
    if not argv:
        raise SystemExit("usage: [--first-seed S] PLINTH_BINARY [RUNS_PER_CASE] [CASE_FILTER]")
    got = (argv[0], int(argv[1]) if len(argv) > 1 else 100, argv[2] if len(argv) > 2 else "")
    return (*got, first) if first_seed else got


def jobs():
    """Parallel workers: $BENCH_JOBS, default the CPU count."""
    return int(os.environ.get("BENCH_JOBS", os.cpu_count() or 1))


def parallel(one, seeds):
    """[one(seed) for seed in seeds], run over `jobs()` threads, in order."""
    with concurrent.futures.ThreadPoolExecutor(jobs()) as pool:
        return list(pool.map(one, seeds))


class Plinth:
    """A `plinth` binary and a scratch directory for the runs it makes."""

    def __init__(self, binary, prefix="bench-"):
        self.binary = binary
        self.work = tempfile.mkdtemp(prefix=prefix)

    def path(self, name):
        """A path `name` inside the scratch directory."""
        return os.path.join(self.work, name)

    def sim(self, machine, out, *args, speeds=SPEEDS):
        """`plinth simulate MACHINE --out OUT --speeds SPEEDS ARGS...` (OUT replaced)."""
        subprocess.run(["rm", "-rf", out], check=True)
        subprocess.run([self.binary, "simulate", machine, "--out", out, "--speeds", speeds,
                        *args], check=True, stdout=subprocess.DEVNULL)

    def identify(self, run, refusal_ok=False):
        """(`plinth identify RUN --json` parsed, exit code); an exit other than 0
        or 2 raises, except exit 1 with `refusal_ok` (identify refused the data,
        e.g. a phasor beyond any machine's: then (None, 1))."""
        p = subprocess.run([self.binary, "identify", run, "--json"], capture_output=True,
                           text=True)
        if refusal_ok and p.returncode == 1:
            return None, 1
        if p.returncode not in (0, 2):
            raise RuntimeError(f"identify {run}: exit {p.returncode}: {p.stderr}")
        return json.loads(p.stdout), p.returncode

    def close(self):
        """Removes the scratch directory."""
        subprocess.run(["rm", "-rf", self.work], check=True)


def data(src, out, *args):
    """scripts/trust_data.py SRC OUT ARGS... (noise, digits, columns, faults on
    a simulated run; OUT replaced)."""
    subprocess.run(["rm", "-rf", out], check=True)
    subprocess.run([sys.executable, DATA, src, out, *args], check=True)


def grid(seed):
    """A speed grid of the digit cases: first speed 5-7.5 Hz and step
    2.375-2.625 Hz drawn from `seed` (digits alone are deterministic: each
    run differs in where its speeds fall on the resonances)."""
    r = random.Random(seed)
    first, step = 5 + 2.5 * r.random(), 2.5 * (0.95 + 0.1 * r.random())
    return f"{first:.4f}:200:{step:.4f}"


def clean_cases(mname, runs):
    """The clean cases of machine `mname`: (case name, runs, how) with how
    ("sim", simulate args...) for the digit cases (run on `grid(seed)`) or
    ("data", trust_data.py args...) on the exact run. `runs` per case
    (heteroscedastic noise at least 200)."""
    cases = [(f"{mname} digits {d}", runs, ("sim", "--digits", d)) for d in ("2", "3", "12")]
    cases += [
        (f"{mname} noise 0.3 %", runs, ("data", "--noise", "0.003")),
        (f"{mname} noise 1 %", runs, ("data", "--noise", "0.01")),
        (f"{mname} noise 3 %", runs, ("data", "--noise", "0.03")),
        (f"{mname} hetero 2 % of |phasor|", max(runs, 200),
         ("data", "--relative-noise", "0.02")),
        (f"{mname} noise 1 % + columns", runs, ("data", "--noise", "0.01", "--columns")),
        (f"{mname} noise 1 % at 3 digits", runs, ("data", "--noise", "0.01", "--digits", "3")),
    ]
    return cases


def clean_run(plinth, machine, exact, how, seed, out):
    """Writes the clean run `how` (a `clean_cases` entry) of `seed` to `out`:
    simulated on its own grid, or made from the exact run `exact`."""
    if how[0] == "sim":
        plinth.sim(machine, out, *how[1:], speeds=grid(seed))
    else:
        data(exact, out, *how[1:], "--seed", str(seed))


def clean_identifications(plinth, n, only, first_seed=1):
    """Every clean case (`clean_cases`, `n` runs each) whose name contains
    `only`: yields (case, runs, [(seed, identify JSON, exit code)] for seeds
    first_seed..first_seed+runs-1), each run made (`clean_run`), identified
    and removed in parallel; each machine's exact run is simulated once."""
    for mname, machine in CLEAN_MACHINES:
        exact = plinth.path(f"exact-{mname}")
        plinth.sim(machine, exact, "--digits", "12")
        for case, runs, how in clean_cases(mname, n):
            if only not in case:
                continue

            def one(seed, how=how, machine=machine, exact=exact):
                out = plinth.path(f"clean-{seed}")
                clean_run(plinth, machine, exact, how, seed, out)
                ident, code = plinth.identify(out)
                subprocess.run(["rm", "-rf", out], check=True)
                return seed, ident, code

            yield case, runs, parallel(one, range(first_seed, first_seed + runs))


def listed(ident, bearing):
    """The speeds identify lists as bad for `bearing` (noise.<b>.outlier_speeds_hz)."""
    return ident["noise"].get(bearing, {}).get("outlier_speeds_hz", [])


def upper95(k, n):
    """One-sided 95 % Clopper-Pearson upper bound of a rate seen k times in n."""
    if n == 0 or k >= n:
        return 1.0
    lo, hi = k / n, 1.0
    for _ in range(60):  # bisection on P(X <= k | p) = 0.05
        mid = 0.5 * (lo + hi)
        cdf = sum(math.comb(n, i) * mid ** i * (1 - mid) ** (n - i) for i in range(k + 1))
        lo, hi = (mid, hi) if cdf > 0.05 else (lo, mid)
    return hi
