#!/usr/bin/env python3
"""Make test data for identify's trust checks from a clean simulated run
(`plinth simulate ... --digits 12`), independently of Plinth's estimator:
noise of several kinds, noise columns, digit reduction, and the faults the
checks must find.

usage: trust_data.py SRC DST [options]

  --noise F            complex Gaussian noise, sd = F x the channel's RMS over speed
  --relative-noise F   heteroscedastic noise: sd = F x |phasor| at each speed
  --columns            write formats.md's noise columns (rel_y_sd ... ped_z_sd)
                       with the sd the noise was drawn with
  --digits D           round every phasor number to D significant digits
  --seed S             noise seed (default 1)
  --flip B:S1,S2,...   negate every channel of bearing B at speeds S1, S2 [Hz]
                       (a keyphasor that triggered half a revolution late)
  --outlier B:S:F      add to every channel of bearing B at speed S [Hz] a
                       phasor F x the channel's RMS at a random phase
  --ped-scale K        multiply every ped phasor by K (1e6: ped in um, rel in m)
  --ped-velocity       write ped velocity i*Omega*X as if it were displacement
  --ped-conjugate      conjugate only the ped phasors (pick-ups read with
                       phase lead, probes with lag)

Noise sd follows formats.md: sd = sqrt(E|n|^2), split equally between the
real and imaginary parts. bearings.csv, truth.json and base.csv are copied
unchanged (base.csv only with --keep-base).
"""
import argparse
import csv
import math
import os
import random
import shutil
import sys

CH = ["rel_y", "rel_z", "ped_y", "ped_z"]


def round_sig(v, d):
    if v == 0 or not math.isfinite(v):
        return v
    return float(f"{v:.{d - 1}e}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--noise", type=float, default=0.0)
    ap.add_argument("--relative-noise", type=float, default=0.0)
    ap.add_argument("--columns", action="store_true")
    ap.add_argument("--digits", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--flip", default="")
    ap.add_argument("--outlier", action="append", default=[])
    ap.add_argument("--ped-scale", type=float, default=1.0)
    ap.add_argument("--ped-velocity", action="store_true")
    ap.add_argument("--ped-conjugate", action="store_true")
    ap.add_argument("--keep-base", action="store_true")
    a = ap.parse_args()

    rng = random.Random(a.seed)
    os.makedirs(a.dst, exist_ok=True)
    for f in ["bearings.csv", "truth.json"] + (["base.csv"] if a.keep_base else []):
        if os.path.exists(os.path.join(a.src, f)):
            shutil.copy(os.path.join(a.src, f), os.path.join(a.dst, f))
    with open(os.path.join(a.src, "measurements.csv")) as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        sys.exit("no rows")

    def z(r, c):
        return complex(float(r[c + "_re"]), float(r[c + "_im"]))

    # RMS over speed of each channel of each bearing.
    rms = {}
    for r in rows:
        for c in CH:
            rms.setdefault((r["bearing"], c), []).append(abs(z(r, c)) ** 2)
    rms = {k: math.sqrt(sum(v) / len(v)) for k, v in rms.items()}

    flips = set()
    if a.flip:
        b, speeds = a.flip.split(":")
        flips = {(b, float(s)) for s in speeds.split(",")}
    outliers = {}
    for o in a.outlier:
        b, s, f = o.split(":")
        outliers[(b, float(s))] = float(f)

    out = []
    for r in rows:
        b = r["bearing"]
        speed = float(r["speed_hz"])
        omega = 2 * math.pi * speed
        new = {"speed_hz": r["speed_hz"], "bearing": b}
        sds = {}
        for c in CH:
            q = z(r, c)
            if c.startswith("ped"):
                if a.ped_velocity:
                    q = 1j * omega * q
                if a.ped_conjugate:
                    q = q.conjugate()
                q *= a.ped_scale
            scale = a.ped_scale if c.startswith("ped") else 1.0
            sd = a.noise * rms[(b, c)] * scale + a.relative_noise * abs(q)
            sds[c] = sd
            if sd > 0:
                s = sd / math.sqrt(2)
                q += complex(rng.gauss(0, s), rng.gauss(0, s))
            if (b, speed) in flips:
                q = -q
            if (b, speed) in outliers:
                mag = outliers[(b, speed)] * rms[(b, c)] * scale
                q += mag * complex(math.cos(ph := rng.uniform(0, 2 * math.pi)), math.sin(ph))
            re, im = q.real, q.imag
            if a.digits:
                re, im = round_sig(re, a.digits), round_sig(im, a.digits)
            new[c + "_re"] = repr(re)
            new[c + "_im"] = repr(im)
        if a.columns:
            for c in CH:
                new[c + "_sd"] = repr(sds[c])
        out.append(new)
    fields = ["speed_hz", "bearing"] + [c + p for c in CH for p in ("_re", "_im")]
    if a.columns:
        fields += [c + "_sd" for c in CH]
    with open(os.path.join(a.dst, "measurements.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(out)


if __name__ == "__main__":
    main()
