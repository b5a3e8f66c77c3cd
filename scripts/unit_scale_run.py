#!/usr/bin/env python3
"""Copy a run directory with a unit mistake on some of its transducers.

Usage:
  python3 scripts/unit_scale_run.py SRC DST FACTOR COLUMNS [BEARINGS]

COLUMNS: `rel` (rel_y and rel_z), `ped`, or one channel (`rel_y`, `ped_z`,
...); several comma-separated. BEARINGS: comma-separated bearing names
(every bearing when left out). Every phasor column of measurements.csv that
starts with one of COLUMNS (its _re and _im, and any `*_sd` noise column of
it) in rows of those bearings is multiplied by FACTOR (e.g. 25.4, 1/25.4,
sqrt2, 1/sqrt2, 1000: a float or `1/X`, X a float or `sqrt2`). Each number is
written with as many significant digits as it was read with, so a run's
digit floor is kept. Every other file of SRC is copied as it is (truth.json
is left as the machine's truth: the mistake is the import's).
"""
import csv
import math
import os
import shutil
import sys


def parse_factor(text):
    def one(t):
        return math.sqrt(2.0) if t == "sqrt2" else float(t)

    if text.startswith("1/"):
        return 1.0 / one(text[2:])
    return one(text)


def digits(text):
    """Significant digits of a number as written."""
    mant = text.strip().lower().split("e")[0].lstrip("+-")
    mant = mant.replace(".", "").lstrip("0")
    return max(len(mant), 1)


def scaled(text, factor):
    v = float(text) * factor
    if v == 0.0:
        return text
    return f"{v:.{digits(text) - 1}e}"


def main():
    if len(sys.argv) not in (5, 6):
        sys.exit(__doc__)
    src, dst, factor, columns = sys.argv[1:5]
    factor = parse_factor(factor)
    prefixes = columns.split(",")
    bearings = set(sys.argv[5].split(",")) if len(sys.argv) == 6 else None
    if os.path.exists(dst):
        shutil.rmtree(dst)
    shutil.copytree(src, dst)
    path = os.path.join(dst, "measurements.csv")
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    chosen = [
        i
        for i, h in enumerate(header)
        if any(h.startswith(p + "_") or h == p for p in prefixes)
        and (h.endswith("_re") or h.endswith("_im") or h.endswith("_sd"))
    ]
    if not chosen:
        sys.exit(f"no column of {header} starts with {prefixes}")
    ib = header.index("bearing")
    seen = set()
    for row in rows[1:]:
        if bearings is not None and row[ib] not in bearings:
            continue
        seen.add(row[ib])
        for i in chosen:
            if row[i].strip():
                row[i] = scaled(row[i], factor)
    if bearings is not None and seen != bearings:
        sys.exit(f"bearings {sorted(bearings - seen)} not in {src}")
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


if __name__ == "__main__":
    main()
