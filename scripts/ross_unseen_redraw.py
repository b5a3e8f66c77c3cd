#!/usr/bin/env python3
"""Noise redraws of one of scripts/ross_unseen.py's cases: its noiseless ROSS
response, fresh complex Gaussian noise at the machine's noise law, the exact
sd as the noise columns (docs/unseen-six.md "Session 46 (lowsnr17)").

Usage: python3 scripts/ross_unseen_redraw.py MACHINE CASE GRIDSEED FIRST LAST OUT

Writes OUT/CASE-exact (the response, no noise, the same columns) and
OUT/CASE-mcS for noise seeds S = FIRST..LAST, each a run directory with the
machine file's pedestals as truth.json. The case must be clean or carry
physical effects only (no runout, delay, flips or outliers). The grid is
the case's at GRIDSEED (most machines' grids do not depend on the seed, so a
ROSS run of the case is this response plus one noise draw). The noise of
seed S comes from numpy's default_rng(STREAM + S), STREAM from $MC_STREAM
(default 10000000): another stream for another case keeps the draws apart.
"""
import json
import math
import os
import sys
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ross_unseen as ru  # noqa: E402


def main():
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    machine, case, gseed, first, last, out = sys.argv[1:]
    if machine not in ru.MACHINES or case not in ru.cases_of(machine):
        sys.exit(f"unknown machine or case: {machine} {case}")
    m = ru.MACHINES[machine]
    with open(ru.machine_file(machine), "rb") as f:
        spec = tomllib.load(f)
    speeds = ru.speeds_of(case, int(gseed), machine)
    effects = ru.effects_of(case, machine)
    physical = [e for e in effects if e[0] in ("frame", "sub_base", "worn_film", "table_scale", "cross")]
    if len(physical) != len(effects):
        sys.exit(f"{case}: only clean cases and physical effects can be redrawn")
    resp, written = ru.respond(spec, speeds, physical)
    names = [b["name"] for b in spec["bearings"]]
    sd = {(b, c): ru.noise_sd(m, c, resp[b][c], speeds) for b in names for c in ru.CHANNELS}
    truth = {"pedestals": ru.nominal_truth(machine), "effects": [], "effect_details": []}
    stream = int(os.environ.get("MC_STREAM", "10000000"))

    def put(d, data):
        ru.write(d, speeds, names, data, sd, {b: 7 for b in names}, written)
        with open(os.path.join(d, "truth.json"), "w") as f:
            json.dump(truth, f, indent=1)
            f.write("\n")

    put(os.path.join(out, f"{case}-exact"), {(b, c): np.asarray(resp[b][c]) for b in names for c in ru.CHANNELS})
    for s in range(int(first), int(last) + 1):
        rng = np.random.default_rng(stream + s)
        data = {}
        for b in names:
            for c in ru.CHANNELS:
                v = np.asarray(resp[b][c])
                noise = rng.standard_normal(len(v)) + 1j * rng.standard_normal(len(v))
                data[(b, c)] = v + noise * sd[(b, c)] / math.sqrt(2)
        put(os.path.join(out, f"{case}-mc{s}"), data)


if __name__ == "__main__":
    main()
