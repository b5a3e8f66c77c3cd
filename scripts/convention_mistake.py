#!/usr/bin/env python3
"""Copies a run directory and makes one convention mistake in its CSV text
(independently of Plinth's own corrections, stdlib only):

    convention_mistake.py SRC DST MISTAKE

MISTAKE: conjugated | swapped_yz | rel_negated | bearing_transposed |
cross_coupling_sign | speed_in_rpm (both files' speeds x 60).
"""
import csv
import os
import shutil
import sys


def neg(s):
    return s[1:] if s.startswith("-") else ("-" + s if s not in ("0", "0.0") else s)


def apply(src, dst, mistake):
    os.makedirs(dst, exist_ok=True)
    for f in os.listdir(src):
        shutil.copy(os.path.join(src, f), os.path.join(dst, f))
    with open(os.path.join(src, "measurements.csv")) as fh:
        rows = list(csv.DictReader(fh))
    with open(os.path.join(src, "bearings.csv")) as fh:
        brows = list(csv.DictReader(fh))
    for r in rows:
        if mistake == "conjugated":
            for c in ["rel_y_im", "rel_z_im", "ped_y_im", "ped_z_im"]:
                r[c] = neg(r[c])
        elif mistake == "swapped_yz":
            for q in ["rel", "ped"]:
                for p in ["re", "im"]:
                    r[f"{q}_y_{p}"], r[f"{q}_z_{p}"] = r[f"{q}_z_{p}"], r[f"{q}_y_{p}"]
        elif mistake == "rel_negated":
            for c in ["rel_y_re", "rel_y_im", "rel_z_re", "rel_z_im"]:
                r[c] = neg(r[c])
        elif mistake == "speed_in_rpm":
            r["speed_hz"] = repr(float(r["speed_hz"]) * 60)
    for r in brows:
        if mistake == "bearing_transposed":
            r["kyz"], r["kzy"] = r["kzy"], r["kyz"]
            r["cyz"], r["czy"] = r["czy"], r["cyz"]
        elif mistake == "cross_coupling_sign":
            for c in ["kyz", "kzy", "cyz", "czy"]:
                r[c] = neg(r[c])
        elif mistake == "speed_in_rpm":
            r["speed_hz"] = repr(float(r["speed_hz"]) * 60)
    for name, rs in [("measurements.csv", rows), ("bearings.csv", brows)]:
        with open(os.path.join(dst, name), "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rs[0].keys()))
            w.writeheader()
            w.writerows(rs)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    apply(sys.argv[1], sys.argv[2], sys.argv[3])
