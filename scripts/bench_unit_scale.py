#!/usr/bin/env python3
"""A unit mistake on some transducers of a run, as identify and diagnose see it.

Usage: python3 scripts/bench_unit_scale.py PLINTH TOML OUT.tsv RUN...

Every RUN (a run directory) is copied with a unit mistake on some of its
transducers (scripts/unit_scale_run.py) and goes through `plinth identify
--json` and `plinth diagnose --json --machine TOML`; one TSV line per case.
The cases, per run: the run as it is (`none`), then for each bearing B of
the run (or $BEARINGS, comma-separated; `all`: every bearing's transducers
of the kind at once) and each KIND of $KINDS (default
`rel,ped,rel_y`: both probes of B, both pick-ups of B, B's y probe alone)
each factor of $FACTORS (default `25.4,1/25.4,2,sqrt2,1000`). $CLEAN_ONLY=1:
only `none` (false alarms on clean or real-table-scale runs). $BENCH_JOBS at
a time (default 1). Scratch under $TMPDIR (default /tmp).

Columns: run, kind, bearing, factor, diagnose trusted, effects named
(effect@bearing), unit_scale (kind@bearing×factor, or `-`), its
`also_fits` (readings that fit as well), the table twin (the bearing
table at the scale's bearing × t, its pedestal with it: `table×t` with
`pass` or `fail`, or `-`), machine-level gap and floor of the final model,
identify's trusted bearings, per bearing identify's k_y against the run's
own (unscaled) identify k_y, and the scales the check cannot see
(`unit_scale_blind`: kind@bearing lo-hi, or `-`).
"""
import concurrent.futures as cf
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def bearings_of(run):
    with open(os.path.join(run, "measurements.csv"), newline="") as f:
        r = csv.DictReader(f)
        seen = []
        for row in r:
            if row["bearing"] not in seen:
                seen.append(row["bearing"])
    return seen


def plinth_json(args):
    p = subprocess.run(args, capture_output=True, text=True)
    try:
        return json.loads(p.stdout)
    except json.JSONDecodeError:
        return {"error": (p.stderr or p.stdout).strip().splitlines()[-1:] or ["?"]}


def one(plinth, toml, run, kind, bearing, factor, tmp):
    if kind == "none":
        d = run
    else:
        d = os.path.join(tmp, f"{os.path.basename(run)}-{kind}-{bearing}-{factor.replace('/', 'i')}")
        at = [] if bearing == "all" else [bearing]
        subprocess.run(
            [sys.executable, os.path.join(HERE, "unit_scale_run.py"), run, d, factor, kind] + at,
            check=True,
        )
    ident = plinth_json([plinth, "identify", d, "--json"])
    diag = plinth_json([plinth, "diagnose", d, "--json", "--machine", toml])
    return ident, diag


def describe_unit(u):
    if not u:
        return "-"
    at = u.get("bearing") or "all"
    s = f"{u['kind']}@{at}x{u['factor']:.4g}"
    if u.get("nearest"):
        s += f"({u['nearest'].split(' ')[0]})"
    return s


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    plinth, toml, out = sys.argv[1:4]
    runs = sys.argv[4:]
    kinds = os.environ.get("KINDS", "rel,ped,rel_y").split(",")
    factors = os.environ.get("FACTORS", "25.4,1/25.4,2,sqrt2,1000").split(",")
    clean_only = os.environ.get("CLEAN_ONLY") == "1"
    jobs = int(os.environ.get("BENCH_JOBS", "1"))
    tmp = tempfile.mkdtemp(prefix="bench_unit_scale_")
    cases = []
    for run in runs:
        cases.append((run, "none", "-", "1"))
        if clean_only:
            continue
        chosen = os.environ.get("BEARINGS")
        for b in chosen.split(",") if chosen else bearings_of(run):
            for k in kinds:
                for f in factors:
                    cases.append((run, k, b, f))
    base_ky = {}
    with open(out, "w") as fo, cf.ThreadPoolExecutor(jobs) as ex:
        fo.write(
            "run\tkind\tbearing\tfactor\ttrusted\tnamed\tunit_scale\talso_fits\ttable_twin\tmgap\tmfloor"
            "\tid_trusted\tid_ky_ratio\tblind\n"
        )
        futs = [ex.submit(one, plinth, toml, *c, tmp) for c in cases]
        for c, fu in zip(cases, futs):
            ident, diag = fu.result()
            run, kind, b, f = c
            if "error" in diag:
                line = [os.path.basename(run), kind, b, f, "error", str(diag["error"])] + [""] * 8
            else:
                named = ",".join(
                    f"{s['effect']}@{s.get('bearing', '')}" for s in diag.get("steps", []) if not s.get("dropped")
                ) or "-"
                u = diag.get("unit_scale")
                alts = ";".join((u or {}).get("also_fits", [])) or "-"
                tw = (u or {}).get("table")
                twin = f"table x{tw['factor']:.4g} {'pass' if tw['passes'] else 'fail'} gap {tw['gap']:.3g}" if tw else "-"
                blind = ";".join(
                    f"{x['kind']}@{x['bearing']} {x['factor_interval'][0]:.3g}-{x['factor_interval'][1]:.3g}"
                    for x in diag.get("unit_scale_blind", [])
                ) or "-"
                peds = ident.get("pedestals", [])
                if kind == "none":
                    base_ky[run] = {p["bearing"]: p["k_y"] for p in peds}
                ratio = ",".join(
                    f"{p['bearing']}:{p['k_y'] / base_ky[run][p['bearing']]:.4g}"
                    for p in peds
                    if base_ky.get(run, {}).get(p["bearing"])
                )
                line = [
                    os.path.basename(run), kind, b, f, str(diag.get("trusted")), named, describe_unit(u), alts, twin,
                    f"{diag.get('machine_gap_after') or float('nan'):.4g}",
                    f"{diag.get('machine_gap_floor') or float('nan'):.4g}",
                    ",".join(p["bearing"] for p in peds if p.get("trusted")) or "-",
                    ratio,
                    blind,
                ]
            fo.write("\t".join(line) + "\n")
            fo.flush()
            print("\t".join(line), flush=True)


if __name__ == "__main__":
    main()
