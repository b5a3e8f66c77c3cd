#!/usr/bin/env python3
"""The stored run tests/data/lowsnr-null-train/ (docs/estimation.md "Session 41 (lowsnr17)"):
one bearing's rows of a `ross_recording.py --null` draw, every STEP-th speed,
numbers written with DIGITS significant digits, so that it stays a few tens
of kB.

Usage: make_lowsnr_null.py NULL_RUN OUT BEARING [STEP [DIGITS]]

NULL_RUN was made (ROSS 2.3.0 venv) by
  ross_recording.py --machine unseen-train REC clean 501 rate=4 revolutions=1
  plinth extract REC/recording.wav --channels REC/channels.toml \
      --bearings REC/bearings.csv --out RUN
  cp REC/truth.json RUN/
  ross_recording.py --null RUN REC NULL_RUN 701
(B1 of unseen-train: a stiff pedestal whose pick-ups read near or below
their noise; the phasors are ROSS's at each row's speed plus complex white
noise of exactly the row's noise column, so the columns are true). OUT gets
measurements.csv (the bearing's rows, noise columns kept), bearings.csv
(the bearing's rows), transducers.csv (the bearing's rows) and truth.json
(the bearing's pedestal). Defaults: STEP 2, DIGITS 5.
"""
import csv
import json
import os
import sys


def short(value, digits):
    return f"{float(value):.{digits - 1}e}"


def main(src, out, bearing, step=2, digits=5):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(src, "measurements.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r["bearing"] == bearing]
    rows.sort(key=lambda r: float(r["speed_hz"]))
    rows = rows[::step]
    names = list(rows[0].keys())
    with open(os.path.join(out, "measurements.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=names, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (v if k == "bearing" else short(v, 8 if k == "speed_hz" else digits))
                        for k, v in r.items()})
    for name in ["bearings.csv", "transducers.csv"]:
        with open(os.path.join(src, name)) as f:
            r = list(csv.reader(f))
        with open(os.path.join(out, name), "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(r[0])
            w.writerows(x for x in r[1:] if x[r[0].index("bearing")] == bearing)
    truth = json.load(open(os.path.join(src, "truth.json")))
    truth["pedestals"] = [p for p in truth["pedestals"] if p["bearing"] == bearing]
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    a = sys.argv[1:]
    if len(a) not in (3, 4, 5):
        sys.exit(__doc__)
    main(a[0], a[1], a[2], *(int(x) for x in a[3:]))
