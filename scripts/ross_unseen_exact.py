#!/usr/bin/env python3
"""A noise-free run of scripts/ross_unseen.py's effect case, at 15 digits.

Usage: python3 scripts/ross_unseen_exact.py MACHINE CASE OUTDIR

The same ROSS response, effect and speed grid as `ross_unseen.py --machine
MACHINE OUTDIR CASE 1`, written without noise, without noise columns and at
15 significant digits: the true phasors of a Monte-Carlo whose noise the test
draws itself (tests/data/ross-unseen/runout-exact, made by
`ross_unseen_exact.py unseen-four runout tests/data/ross-unseen/runout-exact`,
used by host/src/diagnose/ml_final/tests.rs).
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ross_unseen as ru  # noqa: E402


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    machine, case, out = sys.argv[1:]
    if machine not in ru.MACHINES or case not in ru.cases_of(machine):
        sys.exit(f"unknown machine or case: {machine} {case}")
    kind = ru.kind
    effect = kind(case, machine)[0]
    ru.kind = lambda c, m=ru.DEFAULT: (effect, "d15") if c == case else kind(c, m)
    ru.make(out, case, 1, machine)


if __name__ == "__main__":
    main()
