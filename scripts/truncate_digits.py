#!/usr/bin/env python3
"""Copy a run directory with every phasor number of measurements.csv
truncated toward zero to N significant digits (what a logger that cuts
digits writes; the ROSS scripts' dN cases round instead).

    python3 scripts/truncate_digits.py SRC_RUN DST_RUN N [round]

(with `round`: rounded to nearest instead, the rounded control.)

SRC_RUN should carry many digits (e.g. a `clean-d12` run of
scripts/ross_unseen.py). The speed, bearing and any *_sd columns are kept
as they are; bearings.csv and truth.json are copied. Session 41
(docs/trust-lack-of-fit.md "Session 41 (d3trust17)"): the truncated clean runs on which the
false alarms of diagnose's lack-of-fit rule were measured."""
import csv
import decimal
import os
import shutil
import sys

PHASOR = ("rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im",
          "ped_y_re", "ped_y_im", "ped_z_re", "ped_z_im")


def truncate(text, digits, mode=decimal.ROUND_DOWN):
    """`text` (a decimal number) cut toward zero to `digits` significant
    digits, written in scientific notation."""
    d = decimal.Decimal(text)
    if d == 0:
        return "0"
    exp = d.adjusted()
    q = decimal.Decimal(1).scaleb(exp - digits + 1)
    t = d.quantize(q, rounding=mode)
    if t == 0:
        return "0"
    return f"{t:.{digits - 1}e}"


def main():
    if len(sys.argv) not in (4, 5) or sys.argv[4:] not in ([], ["round"]):
        sys.exit(__doc__)
    src, dst, digits = sys.argv[1], sys.argv[2], int(sys.argv[3])
    mode = decimal.ROUND_HALF_EVEN if sys.argv[4:] == ["round"] else decimal.ROUND_DOWN
    if digits < 1:
        sys.exit("N must be at least 1")
    os.makedirs(dst, exist_ok=True)
    for name in os.listdir(src):
        if name != "measurements.csv":
            shutil.copy(os.path.join(src, name), os.path.join(dst, name))
    with open(os.path.join(src, "measurements.csv"), newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    cols = [i for i, h in enumerate(header) if h in PHASOR]
    with open(os.path.join(dst, "measurements.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for r in rows[1:]:
            w.writerow([truncate(v, digits, mode) if i in cols else v for i, v in enumerate(r)])


if __name__ == "__main__":
    main()
