#!/usr/bin/env python3
"""Issue 17's Done-when on a machine nobody tuned to (docs/unseen.md).

Usage: python3 scripts/bench_unseen.py [--machine NAME] PLINTH RUNS_DIR [SEEDS [CASES...]]

NAME: a machine of scripts/ross_unseen.py (default unseen-four). RUNS_DIR
holds run directories CASE-SEED made by scripts/ross_unseen.py (ROSS
2.3.0); missing ones are made first. SEEDS: every case uses seeds 1..SEEDS
(default 5), except unseen-four's clean-d3: 1..4 (its seed shifts the speed
grid); SEEDS given as FIRST-LAST (e.g. 91-92) uses those seeds for every
case (fresh seeds nobody has looked at). Every run goes through `plinth identify --json` and `plinth diagnose
--json --machine FILE` (the machine's nominal file: rigid ground, the drawn
clearances, the table as supplied; without --machine when
$BENCH_DIAGNOSE_PLAIN=1; not at all when $BENCH_IDENTIFY_ONLY=1), $BENCH_JOBS at a
time (default 2).
Prints per case:

identify: runs exiting 2; per bearing how often untrusted; runs whose
  flagged bearings are exactly the expected ones; "ok but wrong" = a
  pedestal printed ok (trusted) with k_y, k_z or m more than 3 of its ±
  from the ROSS truth (confidently wrong); flipped (and outlier) speeds
  listed exactly: every bearing lists exactly its flipped and outlier
  speeds.
± coverage: RMS over the runs of (value − truth)/± of k_y, k_z, m, c_y, c_z
  per bearing (about 1 when the ± mean what they say).
diagnose: named right (exactly the expected effects, each at its bearing,
  a base at any bearing), named wrong (something else named, or an
  expected effect at another bearing), partly (a subset, nothing wrong),
  missed (nothing named); named wrong with the verdict trusted (confidently
  wrong); untrusted verdicts; the worst k/m error of the
  named-right runs' final pedestals; runs whose verdict is trusted while
  a final pedestal (`pedestals_after`) has k_y, k_z or m more than 3 of
  its ± from the truth (confidently off), and the same for c_y, c_z
  (those given with a ±); the flipped speeds diagnose lists
  (`flipped_speeds_hz`: exactly the truth's on the flips case, any listed
  on the others); seconds per run.
"""
import concurrent.futures as cf
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Per machine, case: (effects diagnose should name as (effect, bearing);
# bearings identify should flag (None: no expectation beyond "not every
# bearing"))
EXPECT_FOUR = {
    "clean-w1": ([], set()),
    "clean-w1c": ([], set()),
    "clean-d3": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B3")], {"B3"}),
    "table": ([("bearing_coefficients", "B2")], None),
    "cross": ([("pedestal_cross_coupling", "B4")], None),
    "runout": ([("probe_runout", "B3")], None),
    "flips": ([], set()),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B2")], None),
}
EXPECT_OVERHUNG = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B1")], {"B1"}),
    "table-film": ([("bearing_coefficients", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B1")], {"B1"}),
    "cross": ([("pedestal_cross_coupling", "B1")], {"B1"}),
    "runout": ([("probe_runout", "B2")], {"B2"}),
    "delay": ([("sensor_delay", "B1")], {"B1"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base-runout-delay": ([("foundation_coupling", ""), ("probe_runout", "B1"), ("sensor_delay", "B2")],
                          {"B1", "B2"}),
    "cross-runout": ([("pedestal_cross_coupling", "B2"), ("probe_runout", "B1")], {"B1", "B2"}),
}
EXPECT_TRAIN = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-film": ([("bearing_coefficients", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B3")], {"B3"}),
    "cross": ([("pedestal_cross_coupling", "B3")], {"B3"}),
    "runout": ([("probe_runout", "B1")], {"B1"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B1")], {"B1", "B2", "B3"}),
    "cross-delay": ([("pedestal_cross_coupling", "B2"), ("sensor_delay", "B3")], {"B2", "B3"}),
}
EXPECT_FLEX = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B1")], {"B1"}),
    "table-scale": ([("bearing_coefficients", "B2")], {"B2"}),
    "cross": ([("pedestal_cross_coupling", "B2")], {"B2"}),
    "runout": ([("probe_runout", "B1")], {"B1"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "delay-runout": ([("sensor_delay", "B1"), ("probe_runout", "B2")], {"B1", "B2"}),
    "base": ([("foundation_coupling", "")], None),
}
EXPECT_FIVE = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-film": ([("bearing_coefficients", "B1")], {"B1"}),
    "table-scale": ([("bearing_coefficients", "B2")], {"B2"}),
    "cross": ([("pedestal_cross_coupling", "B1")], {"B1"}),
    "runout": ([("probe_runout", "B2")], {"B2"}),
    "delay": ([("sensor_delay", "B1")], {"B1"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
}
EXPECT_SIX = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-film": ([("bearing_coefficients", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B3")], {"B3"}),
    "cross": ([("pedestal_cross_coupling", "B1")], {"B1"}),
    "runout": ([("probe_runout", "B3")], {"B3"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
    "base-delay": ([("foundation_coupling", ""), ("sensor_delay", "B1")], None),
    "cross-runout": ([("pedestal_cross_coupling", "B3"), ("probe_runout", "B1")], {"B1", "B3"}),
}
# unseen-seven: table-thermal and sweep are departures no library effect
# names (docs/unseen-seven.md): for table-thermal the nearest is a
# bearing-table correction at any bearing; for sweep nothing is expected
# (what matters there is the "trusted, after > 3 ± off" column)
EXPECT_SEVEN = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B1")], {"B1"}),
    "table-film": ([("bearing_coefficients", "B3")], {"B3"}),
    "cross": ([("pedestal_cross_coupling", "B2")], {"B2"}),
    "runout": ([("probe_runout", "B1")], {"B1"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B3")], None),
    "cross-delay": ([("pedestal_cross_coupling", "B3"), ("sensor_delay", "B1")], {"B1", "B3"}),
    "table-thermal": ([("bearing_coefficients", "")], None),
    "ped-delay": ([("sensor_delay", "B3")], {"B3"}),
    "sweep": ([], None),
}
# unseen-eight: probe-axes, kp-lag and corr-noise are departures no library
# effect names (docs/unseen-eight.md): nothing is expected by name (what
# matters is whether what is printed trusted is right)
EXPECT_EIGHT = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B1")], {"B1"}),
    "cross": ([("pedestal_cross_coupling", "B2")], {"B2"}),
    "runout": ([("probe_runout", "B1")], {"B1"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B2")], None),
    "cross-delay": ([("pedestal_cross_coupling", "B1"), ("sensor_delay", "B2")], {"B1", "B2"}),
    "probe-axes": ([], None),
    "kp-lag": ([], None),
    "corr-noise": ([], None),
}
# unseen-nine: ped-drift and probe-gain are departures no library effect
# names (docs/unseen-nine.md): nothing is expected by name; runout-drift is
# a runout that changes along the run, the library's nearest is
# probe_runout at B2
EXPECT_NINE = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B1")], {"B1"}),
    "cross": ([("pedestal_cross_coupling", "B2")], {"B2"}),
    "runout": ([("probe_runout", "B1")], {"B1"}),
    "delay": ([("sensor_delay", "B2")], {"B2"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B2")], None),
    "cross-delay": ([("pedestal_cross_coupling", "B1"), ("sensor_delay", "B2")], {"B1", "B2"}),
    "ped-drift": ([], None),
    "probe-gain": ([], None),
    "runout-drift": ([("probe_runout", "B2")], {"B2"}),
    "ped-drift-up": ([], None),
}
# unseen-ten: probe-gain and speed-lag have no library name (nothing
# expected by name; identify untrusting the bearing is right for probe-gain)
EXPECT_TEN = {
    "clean-w1": ([], set()),
    "sub-base": ([("pedestal_sub_base", "B2")], {"B2"}),
    "table-scale": ([("bearing_coefficients", "B1")], {"B1"}),
    "cross": ([("pedestal_cross_coupling", "B1")], {"B1"}),
    "runout": ([("probe_runout", "B2")], {"B2"}),
    "delay": ([("sensor_delay", "B1")], {"B1"}),
    "flips": ([], set()),
    "outlier": ([], set()),
    "base": ([("foundation_coupling", "")], None),
    "probe-gain": ([], None),
    "speed-lag": ([], None),
    "base-runout": ([("foundation_coupling", ""), ("probe_runout", "B1")], None),
    "cross-delay": ([("pedestal_cross_coupling", "B2"), ("sensor_delay", "B1")], {"B1", "B2"}),
}
EXPECT = {"unseen-four": EXPECT_FOUR, "unseen-overhung": EXPECT_OVERHUNG, "unseen-train": EXPECT_TRAIN,
          "unseen-flex": EXPECT_FLEX, "unseen-five": EXPECT_FIVE, "unseen-six": EXPECT_SIX,
          "unseen-seven": EXPECT_SEVEN, "unseen-eight": EXPECT_EIGHT, "unseen-nine": EXPECT_NINE,
          "unseen-ten": EXPECT_TEN}


sys.path.insert(0, os.path.join(ROOT, "scripts"))
import ross_unseen  # noqa: E402

MACHINE = ross_unseen.DEFAULT
DIAGNOSE_MACHINE = []  # ["--machine", FILE] unless $BENCH_DIAGNOSE_PLAIN=1


def kind(case):
    return ross_unseen.kind(case, MACHINE)


def expect(case):
    effect = kind(case)[0]
    return EXPECT[MACHINE]["clean-w1" if effect == "clean" else effect]


def listed_exactly(r, listed=None):
    """Every bearing lists exactly its flipped and outlier speeds in `listed`
    (speeds per bearing: identify's list unless another is given)."""
    listed = r["listed"] if listed is None else listed
    want = {}
    for d in r["truth"]["effect_details"]:
        if d["name"] in ("keyphasor_flip", "outlier_speed"):
            want.setdefault(d["bearing"], []).extend(d["parameters"].values())
    return all(sorted(listed.get(b, [])) == sorted(want.get(b, []))
               for b in set(want) | set(listed))


def run_json(args):
    t0 = time.perf_counter()
    p = subprocess.run(args, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if p.returncode not in (0, 2):
        return None, p.returncode, dt, p.stderr.strip().splitlines()[-1:]
    return json.loads(p.stdout), p.returncode, dt, []


COVERED = ("k_y", "k_z", "m", "c_y", "c_z")  # the values whose ± coverage is measured


def km_keys(ped):
    """(key, truth key) of the stiffnesses and mass(es) `ped` gives: m, or
    m_y and m_z where diagnose fitted a mass per direction
    (pedestal_mass_anisotropy), each against the truth's m."""
    masses = [k for k in ("m_y", "m_z") if k in ped] if "m" not in ped else ["m"]
    return [("k_y", "k_y"), ("k_z", "k_z")] + [(k, "m") for k in masses]


def worst_z(ped, truth):
    """Largest |value − truth|/± of k_y, k_z, m (or m_y, m_z) (inf where a
    ± is 0 or missing: a value given without an uncertainty)."""
    t = next(t for t in truth["pedestals"] if t["bearing"] == ped["bearing"])
    se = ped["std_err"]
    return max(abs(ped[k] - t[tk]) / se[k] if se.get(k, 0) > 0 else math.inf for k, tk in km_keys(ped))


def worst_c_z(ped, truth):
    """Largest |value − truth|/± of c_y, c_z among those given with a ± (a
    damping held at zero has none; 0 when neither has one)."""
    t = next(t for t in truth["pedestals"] if t["bearing"] == ped["bearing"])
    se = ped["std_err"]
    return max([abs(ped[k] - t[k]) / se[k] for k in ("c_y", "c_z") if se.get(k, 0) > 0], default=0.0)


def worst_rel(ped, truth, get):
    """Largest relative error of k_y, k_z, m against the truth."""
    t = next(t for t in truth["pedestals"] if t["bearing"] == ped["bearing"])
    return max(abs(get(ped, k) / t[tk] - 1.0) for k, tk in km_keys(ped))


def imported(b, run):
    """A field case (RUN/field/: a 1X vector table, its layout and the
    bearing table) goes through `plinth import` into RUN first, as a field
    engineer's data would; returns the import's error lines (empty if
    none)."""
    field = os.path.join(run, "field")
    if not os.path.isdir(field) or os.path.exists(os.path.join(run, "measurements.csv")):
        return []
    p = subprocess.run([b, "import", os.path.join(field, "vectors.csv"), "--layout",
                        os.path.join(field, "layout.toml"), "--bearings", os.path.join(field, "bearings.csv"),
                        "--out", run, "--force"], capture_output=True, text=True)
    return [] if p.returncode == 0 else ["import: " + l for l in p.stderr.strip().splitlines()[-1:]]


def one(b, run):
    with open(os.path.join(run, "truth.json")) as f:
        truth = json.load(f)
    ierr0 = imported(b, run)
    ident, icode, it, ierr = run_json([b, "identify", run, "--json"])
    if os.environ.get("BENCH_IDENTIFY_ONLY", "0") == "1":
        diag, dcode, dt, derr = None, None, 0.0, []
    else:
        diag, dcode, dt, derr = run_json([b, "diagnose", run, "--json"] + DIAGNOSE_MACHINE)
    r = {"run": run, "truth": truth, "icode": icode, "dcode": dcode, "it": it, "dt": dt,
         "err": ierr0 + ierr + derr}
    if ident is not None:
        r["untrusted"] = sorted(p["bearing"] for p in ident["pedestals"] if not p["trusted"])
        r["listed"] = {k: v.get("outlier_speeds_hz", []) for k, v in ident["noise"].items()}
        r["kinds"] = sorted({w["kind"] for p in ident["pedestals"] for w in p["warnings"]})
        wrong = []
        for p in ident["pedestals"]:
            t = next(t for t in truth["pedestals"] if t["bearing"] == p["bearing"])
            z = worst_z(p, truth)
            rel = worst_rel(p, truth, lambda q, k: q[k])
            r.setdefault("ident_err", {})[p["bearing"]] = (rel, z, p["trusted"])
            for k in COVERED:
                if p["std_err"][k] > 0:
                    r.setdefault("zs", {})[(p["bearing"], k)] = (p[k] - t[k]) / p["std_err"][k]
            if p["trusted"] and z > 3.0:
                wrong.append(p["bearing"])
        r["ok_wrong"] = wrong
    if diag is not None:
        r["named"] = [(s["effect"], s["bearing"]) for s in diag["steps"] if not s.get("dropped")]
        r["dtrusted"] = diag["trusted"]
        r["dlisted"] = diag.get("flipped_speeds_hz", {})
        r["gap"] = (diag["gap_before"], diag["gap_after"])
        r["after_err"] = max(worst_rel(p, truth, lambda q, k: q[k])
                             for p in diag["pedestals_after"])
        r["after_each"] = {p["bearing"]: worst_rel(p, truth, lambda q, k: q[k])
                           for p in diag["pedestals_after"]}
        r["after_z"] = {p["bearing"]: worst_z(p, truth) for p in diag["pedestals_after"]}
        # the final pedestals more than 3 ± off while the verdict is trusted (confidently wrong)
        r["after_off"] = sorted(bb for bb, z in r["after_z"].items() if z > 3.0) if diag["trusted"] else []
        # the same for the final dampings (a missed phase error reads as one)
        r["after_c_z"] = {p["bearing"]: worst_c_z(p, truth) for p in diag["pedestals_after"]}
        r["after_c_off"] = sorted(bb for bb, z in r["after_c_z"].items() if z > 3.0) if diag["trusted"] else []
    return r


def judge(case, r):
    want, _ = expect(case)
    named = r.get("named")
    if named is None:
        return "error"
    if not named:
        return "missed" if want else "right"
    def match(n, w):
        return n[0] == w[0] and (w[1] == "" or n[1] == w[1])
    extra = [n for n in named if not any(match(n, w) for w in want)]
    found = [w for w in want if any(match(n, w) for n in named)]
    if extra:
        return "wrong"
    return "right" if len(found) == len(want) else "partly"


def main():
    global MACHINE
    args = sys.argv[1:]
    if args[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return
    if args[:1] == ["--machine"] and len(args) >= 2:
        MACHINE, args = args[1], args[2:]
    if MACHINE not in ross_unseen.MACHINES:
        sys.exit(f"--machine {MACHINE}: not one of {', '.join(ross_unseen.MACHINES)}")
    global DIAGNOSE_MACHINE
    if os.environ.get("BENCH_DIAGNOSE_PLAIN", "0") != "1":
        DIAGNOSE_MACHINE = ["--machine", ross_unseen.machine_file(MACHINE)]
    if len(args) < 2:
        sys.exit("usage: bench_unseen.py [--machine NAME] PLINTH RUNS_DIR [SEEDS [CASES...]] (--help for more)")
    b, runs = args[0], args[1]
    try:
        first, _, last = (args[2] if len(args) > 2 else "5").partition("-")
        seeds = range(int(first), int(last) + 1) if last else range(1, int(first) + 1)
    except ValueError:
        sys.exit(f"SEEDS: {args[2]!r} is neither a whole number nor FIRST-LAST")
    cases = args[3:] or list(ross_unseen.cases_of(MACHINE))
    bearings = [t["bearing"] for t in ross_unseen.nominal_truth(MACHINE)]
    todo, make = [], {}
    for case in cases:
        these = range(1, 5) if (MACHINE, case) == ("unseen-four", "clean-d3") and seeds.start == 1 else seeds
        missing = tuple(str(s) for s in these if not os.path.isdir(os.path.join(runs, f"{case}-{s}")))
        if missing:
            make.setdefault(missing, []).append(case)
        todo += [(case, os.path.join(runs, f"{case}-{s}")) for s in these]
    for missing, group in make.items():  # one ROSS process per group: its responses are cached
        subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "ross_unseen.py"), "--machine", MACHINE,
                        runs, ",".join(group), *missing], check=True, capture_output=True)
    jobs = int(os.environ.get("BENCH_JOBS", "2"))
    t0 = time.time()
    with cf.ThreadPoolExecutor(jobs) as ex:
        results = list(ex.map(lambda cr: (cr[0], one(b, cr[1])), todo))
    by = {}
    for case, r in results:
        by.setdefault(case, []).append(r)
    print("identify (plinth identify --json):")
    listing = "flips listed exactly" if MACHINE == "unseen-four" else "flips/outlier listed exactly"
    print(f"| case | runs | exit 2 | untrusted per bearing {'/'.join(bearings)} | flagged as expected "
          f"| ok but wrong (> 3 ±) | {listing} |")
    print("|---|---|---|---|---|---|---|")
    for case in cases:
        rs = by[case]
        n = len(rs)
        ex2 = sum(r["icode"] == 2 for r in rs)
        per = "/".join(str(sum(bb in r.get("untrusted", []) for r in rs)) for bb in bearings)
        want = expect(case)[1]
        exp = "-" if want is None else str(sum(set(r.get("untrusted", [])) == want for r in rs))
        okw = sum(bool(r.get("ok_wrong")) for r in rs)
        okw_b = sorted({bb for r in rs for bb in r.get("ok_wrong", [])})
        fl = "-"
        if kind(case)[0] in ("flips", "outlier"):
            fl = str(sum(listed_exactly(r) for r in rs if "listed" in r))
        if kind(case)[0] in ("clean", "flips"):
            listed = sum(any(v for v in r.get("listed", {}).values()) for r in rs)
            if kind(case)[0] == "clean":
                fl = f"(any listed: {listed})"
        print(f"| {case} | {n} | {ex2} | {per} | {exp}/{n} | {okw} {okw_b if okw_b else ''} | {fl} |")
    print()
    print("± coverage: RMS over the runs of (identify's value − truth)/± (1 = the ± mean what they "
          "say; every run, trusted or not):")
    print(f"| case | {' | '.join(f'{bb} {k}' for bb in bearings for k in COVERED)} |")
    print("|---|" + "---|" * (len(bearings) * len(COVERED)))
    for case in cases:
        cells = []
        for bb in bearings:
            for k in COVERED:
                z = [r["zs"][(bb, k)] for r in by[case] if (bb, k) in r.get("zs", {})]
                cells.append(f"{math.sqrt(sum(v * v for v in z) / len(z)):.2f}" if z else "-")
        print(f"| {case} | {' | '.join(cells)} |")
    print()
    if os.environ.get("BENCH_IDENTIFY_ONLY", "0") == "1":
        return
    how = " ".join(["--json"] + [os.path.basename(a) for a in DIAGNOSE_MACHINE])
    print(f"diagnose (plinth diagnose {how}):")
    print("| case | runs | named right | named wrong | wrong and trusted | partly | missed | untrusted "
          "| worst k/m error after (right runs) | trusted, after > 3 ± off | trusted, a damping after > 3 ± off "
          "| flips listed exactly | s/run |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for case in cases:
        rs = by[case]
        n = len(rs)
        v = [judge(case, r) for r in rs]
        untr = sum(not r.get("dtrusted", True) for r in rs)
        errs = [r["after_err"] for r, j in zip(rs, v) if j == "right" and "after_err" in r]
        worst = f"{100 * max(errs):.2f} %" if errs else "-"
        wrong = sorted({str(r.get("named")) for r, j in zip(rs, v) if j in ("wrong", "partly")})
        sec = sum(r["dt"] for r in rs) / n
        fl = f"(any listed: {sum(any(r.get('dlisted', {}).values()) for r in rs)})"
        if kind(case)[0] == "flips":
            fl = str(sum(listed_exactly(r, r.get("dlisted", {})) for r in rs))
        wt = sum(j == "wrong" and r.get("dtrusted", False) for r, j in zip(rs, v))
        off = sum(bool(r.get("after_off")) for r in rs)
        off_b = sorted({bb for r in rs for bb in r.get("after_off", [])})
        coff = sum(bool(r.get("after_c_off")) for r in rs)
        coff_b = sorted({bb for r in rs for bb in r.get("after_c_off", [])})
        print(f"| {case} | {n} | {v.count('right')} | {v.count('wrong')} | {wt} | {v.count('partly')} | "
              f"{v.count('missed')} | {untr} | {worst} | {off} {off_b if off_b else ''} | "
              f"{coff} {coff_b if coff_b else ''} | {fl} | {sec:.0f} |" + (f" {'; '.join(wrong)}" if wrong else ""))
    for case, r in results:
        if r["err"]:
            print(f"ERROR {r['run']}: {r['err']}")
    print()
    print("per run (case, identify untrusted, listed, diagnose named, trusted, gap, worst after):")
    for case, r in results:
        listed = {k: v for k, v in r.get("listed", {}).items() if v}
        gap = r.get("gap", (float("nan"),) * 2)
        print(f"  {os.path.basename(r['run'])}: identify exit {r['icode']} untrusted {r.get('untrusted')} "
              f"listed {listed} ok_wrong {r.get('ok_wrong')}; diagnose {r.get('named')} trusted "
              f"{r.get('dtrusted')} gap {gap[0]:.3g}->{gap[1]:.3g} after {100 * r.get('after_err', math.nan):.2f} % "
              f"z {max(r.get('after_z', {}).values(), default=math.nan):.2f} "
              f"c z {max(r.get('after_c_z', {}).values(), default=math.nan):.2f} "
              f"({r['it']:.1f} + {r['dt']:.0f} s)")
    print(f"total {time.time() - t0:.0f} s wall")


if __name__ == "__main__":
    main()
