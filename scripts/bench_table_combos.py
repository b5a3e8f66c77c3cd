#!/usr/bin/env python3
"""A wrong bearing table on a base, or beside another effect at its bearing
(issue 17; docs/diagnose-bearing-table.md "The table correction beside other effects").

Usage: python3 scripts/bench_table_combos.py PLINTH RUNS_DIR [SEEDS [CASES...]]

Extra cases of the first unseen machine (unseen-four, scripts/ross_unseen.py:
ROSS 2.3.0, 1 % white noise with the *_sd columns, or 3 digits for the -d3
cases), made here with ross_unseen's own elements and judged by
scripts/bench_unseen.py (its table, its rules):

  base          the shared frame under B1 and B2 alone (a clean control with
                a base: foundation_coupling and nothing else)
  base-table    the frame, and B2's oil-film table written for a clearance
                15 % smaller than the machine's
  base-scale    the frame, and B1's tabulated stiffness 25 % above the
                bearing's (the damping as written)
  table-runout  B2's worn table and probe runout at B2
  scale-runout  B1's table stiffness 25 % high and probe runout at B1

with `-d3` variants (no noise, 3 significant digits). The runs are made in
this process (ross_unseen's MACHINES extended here, not in its file: its
seeds for the other cases do not move), then scored by bench_unseen.
"""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import bench_unseen  # noqa: E402
import ross_unseen  # noqa: E402

FRAME = ("frame", ross_unseen.FRAME_FOUR)
WORN_B2 = ("worn_film", "B2", 1.0 / 0.85)
SCALE_B1 = ("table_scale", "B1", 1.0 / 1.25, 1.0)
# case: (effects in ross_unseen's form, what diagnose should name)
COMBOS = {
    "base": ([FRAME], [("foundation_coupling", "")]),
    "base-table": ([FRAME, WORN_B2], [("foundation_coupling", ""), ("bearing_coefficients", "B2")]),
    "base-scale": ([FRAME, SCALE_B1], [("foundation_coupling", ""), ("bearing_coefficients", "B1")]),
    "table-runout": ([WORN_B2, ("runout", "B2")], [("bearing_coefficients", "B2"), ("probe_runout", "B2")]),
    "scale-runout": ([SCALE_B1, ("runout", "B1")], [("bearing_coefficients", "B1"), ("probe_runout", "B1")]),
}
MACHINE = "unseen-four"


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    runs = args[1]
    seeds = int(args[2]) if len(args) > 2 else 5
    cases = args[3:] or list(COMBOS)
    m = ross_unseen.MACHINES[MACHINE]
    for name, (effects, named) in COMBOS.items():
        m["effects"][name] = effects
        bench_unseen.EXPECT_FOUR[name] = (named, None)
    for case in cases:
        if case.removesuffix("-d3") not in COMBOS:
            sys.exit(f"{case}: not one of {', '.join(COMBOS)} (or -d3)")
        for s in range(1, seeds + 1):
            out = os.path.join(runs, f"{case}-{s}")
            if not os.path.isdir(out):
                ross_unseen.make(out, case, s, MACHINE)
    sys.argv = [sys.argv[0], args[0], runs, str(seeds)] + cases
    bench_unseen.main()


if __name__ == "__main__":
    main()
