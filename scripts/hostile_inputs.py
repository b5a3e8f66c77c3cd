#!/usr/bin/env python3
"""Hostile copies of a run directory for comparing two readers
(scripts/compare-identify.sh with HOSTILE=1): one field of either table
replaced by a text a reader may meet (refused, special, or read: signs,
points, exponents at and beyond i32, 17-20 digits, subnormals, the largest
double and beyond, padding, BOMs, other scripts' digits), each field in
turn at every column; and whole files broken (BOM, CRLF, CR only, cut in
half, empty lines, a 0xff byte, a NUL byte).

    scripts/hostile_inputs.py RUN OUT   (OUT/NNN/ for each case)
"""
import os
import shutil
import sys

FIELDS = [
    "", ".", "-", "+", "-.", "+.e1", "e5", "1e", "1e+", "1.2.3", "0x10", "1_000",
    " 1.5e-9", "1.5e-9 ", "\t1.5e-9", "1.5\ufeffe-9", "\ufeff1.5e-9", "1.5e-9\r",
    "inf", "-inf", "infinity", "NaN", "nan", "1e308", "1.8e308", "-1.8e308", "5e-324",
    "2.4703282292062328e-324", "1e-400", "-1e-400", "1e99999999999", "1e-99999999999",
    "1e2147483647", "10e2147483647", "0.001e-2147483648", "1e2147483648",
    "1" * 1000, "0" * 500 + "1.25e-9", "\u0661", "1,5", '"1.5e-9"', "1.5e-9x",
    "0", "-0", "+0", "0.0e0", "1", "-1", "+1.5e-9", ".5e-9", "5.e-9", "1.E-9",
    "12345678901234567890e-28", "1234567890123456789e-27", "9999999999999999999e-28",
    "6.9353032815096430000e-9", "6.935303281509643e-9", "-2.4282161458489725e-9",
    "2.2250738585072011e-308", "1.7976931348623159e308", "9007199254740993e-24",
    "1.00000000000000011102230246251565404236316680908203125",
    "0.000000000000000000000000000001e21", "123.456e-11", "-0.000000001234",
]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    base, out = sys.argv[1], sys.argv[2]
    count = 0

    def write(name, data):
        nonlocal count
        d = os.path.join(out, f"{count:03d}")
        os.makedirs(d)
        for other in ("measurements.csv", "bearings.csv", "truth.json"):
            if other != name and os.path.exists(os.path.join(base, other)):
                shutil.copy(os.path.join(base, other), d)
        with open(os.path.join(d, name), "wb") as f:
            f.write(data if isinstance(data, bytes) else data.encode())
        count += 1

    for name in ("measurements.csv", "bearings.csv"):
        with open(os.path.join(base, name), newline="") as f:
            lines = f.read().split("\n")
        body = [i for i, line in enumerate(lines) if i > 0 and line]
        width = len(lines[0].split(","))
        for i, field in enumerate(FIELDS):
            # Every column but the bearing's in turn, rows spread out.
            column = [c for c in range(width) if c != 1][i % (width - 1)]
            row = body[(7 * i) % len(body)]
            cells = lines[row].split(",")
            cells[column] = field
            edited = lines[:row] + [",".join(cells)] + lines[row + 1 :]
            write(name, "\n".join(edited))
        text = "\n".join(lines)
        for broken in (
            "\ufeff" + text,
            text.replace("\n", "\r\n"),
            text.replace("\n", "\r"),
            text[: len(text) // 2],
            text.replace("\n", "\n\n", 5),
        ):
            write(name, broken)
        raw = text.encode()
        write(name, raw[:200] + b"\xff" + raw[200:])
        write(name, raw[:200] + b"\x00" + raw[200:])
    print(f"{count} hostile runs in {out}")


if __name__ == "__main__":
    main()
