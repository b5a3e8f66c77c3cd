#!/usr/bin/env python3
"""Run directories of machines on flexible bases, made by ROSS, not Plinth.

Usage:  python3 tests/reference/ross/foundation/make_runs.py
        (ROSS 2.3.0 on Python 3.11 with plotly<6; writes the run directories
        beside this script; deterministic: fixed seeds)

The machines (fd-*.toml, Plinth machine-file syntax read with tomllib) are
built in ROSS by ../make_reference.py's `build` (Timoshenko shaft, disks,
bearing -> pedestal point mass -> base point mass -> ground). This script
then writes each run directory itself, following the repository's
docs/formats.md directly: `measurements.csv` with rel = rotor
minus pedestal and ped = absolute pedestal motion, q(t) = Re{Q e^{iWt}},
y vertical, z horizontal; `bearings.csv`; `truth.json` with the pedestals,
the bases and `effects: ["foundation_coupling"]` (none for the rigid
control). Nothing of Plinth's simulator, writer or noise model is used, so
host/tests/foundation_ross.rs checks Plinth against another program.

Variants per machine:
  <name>-noisy/   complex Gaussian noise of NOISE_FRACTION of each channel's
                  RMS over the run on every rel and ped phasor (split
                  equally between re and im), written with 7 significant
                  digits and the formats.md noise columns *_sd.
  <name>-3digits/ (fd-skid-two only) no added noise, 3 significant digits,
                  no noise columns: the reader must take the noise from the
                  digits.
"""
import json
import math
import os
import sys
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from make_reference import build, node_of  # noqa: E402

NOISE_FRACTION = 0.005
MACHINES = {
    # name: (speeds [Hz], variants)
    "fd-skid-two": (np.arange(5.0, 100.0 + 1e-9, 1.0), ("noisy", "3digits")),
    "fd-frame-three": (np.arange(5.0, 70.0 + 1e-9, 1.0), ("noisy",)),
    "fd-rigid-three": (np.arange(5.0, 70.0 + 1e-9, 1.0), ("noisy",)),
}
CHANNELS = ("rel_y", "rel_z", "ped_y", "ped_z")


def sig(v, digits):
    return f"{v:.{digits - 1}e}"


def respond(spec, speeds):
    rotor, x, unb, coefs = build(spec, list(map(float, speeds)))
    w = 2 * math.pi * np.asarray(speeds)
    resp = rotor.run_unbalance_response([u[0] for u in unb], [u[1] for u in unb],
                                        [math.radians(u[2]) for u in unb], frequency=w)
    X = resp.forced_resp
    nd = rotor.number_dof
    pm = {e.tag: e for e in rotor.point_mass_elements}
    n_nodes = len(x)
    out = {}
    for i, b in enumerate(spec["bearings"]):
        n = node_of(b, x)
        pn = n_nodes + i
        gi = pm[f"ped_{b['name']}"].dof_global_index
        py, pz = X[gi[f"x_{pn}"]], X[gi[f"y_{pn}"]]
        sy, sz = X[nd * n + 0], X[nd * n + 1]
        out[b["name"]] = {"rel_y": sy - py, "rel_z": sz - pz, "ped_y": py, "ped_z": pz}
    return out, coefs


def write_run(path, spec, speeds, resp, coefs, variant, rng):
    os.makedirs(path, exist_ok=True)
    names = [b["name"] for b in spec["bearings"]]
    noisy = variant == "noisy"
    digits = 7 if noisy else 3
    sd = {}
    data = {}
    for b in names:
        for c in CHANNELS:
            v = resp[b][c]
            s = NOISE_FRACTION * math.sqrt(np.mean(np.abs(v) ** 2)) if noisy else 0.0
            sd[(b, c)] = s
            n = (rng.standard_normal(len(v)) + 1j * rng.standard_normal(len(v))) * s / math.sqrt(2)
            data[(b, c)] = v + n
    with open(os.path.join(path, "measurements.csv"), "w") as f:
        head = "speed_hz,bearing," + ",".join(f"{c}_re,{c}_im" for c in CHANNELS)
        if noisy:
            head += "," + ",".join(f"{c}_sd" for c in CHANNELS)
        f.write(head + "\n")
        for j, s in enumerate(speeds):
            for b in names:
                row = [f"{s:g}", b]
                for c in CHANNELS:
                    q = data[(b, c)][j]
                    row += [sig(q.real, digits), sig(q.imag, digits)]
                if noisy:
                    row += [sig(sd[(b, c)], 4) for c in CHANNELS]
                f.write(",".join(row) + "\n")
    with open(os.path.join(path, "bearings.csv"), "w") as f:
        f.write("speed_hz,bearing,kyy,kyz,kzy,kzz,cyy,cyz,czy,czz\n")
        for s in (speeds[0], speeds[-1]):
            for b in names:
                c = coefs[b]
                f.write(",".join([f"{s:g}", b] + [repr(float(c[k][0])) for k in
                                  ("kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz")]) + "\n")
    truth = {"pedestals": [], "effects": [], "source": "ROSS " + __import__("ross").__version__ +
             " via tests/reference/ross/foundation/make_runs.py (" + spec["name"] + ".toml)"}
    for b in spec["bearings"]:
        p = b["pedestal"]
        truth["pedestals"].append({"bearing": b["name"], "k_y": p["k_y"], "k_z": p["k_z"], "m": p["m"],
                                   "c_y": p.get("c_y", 0.0), "c_z": p.get("c_z", 0.0)})
    bases = []
    for base in spec.get("base", []):
        my, mz = (base["m"], base["m"]) if "m" in base else (base["m_y"], base["m_z"])
        bases.append({"name": base["name"],
                      "bearings": [b["name"] for b in spec["bearings"] if b.get("base") == base["name"]],
                      "m_y": my, "m_z": mz, "k_y": base["k_y"], "k_z": base["k_z"],
                      "c_y": base.get("c_y", 0.0), "c_z": base.get("c_z", 0.0), "eta": 0.0})
    if bases:
        truth["bases"] = bases
        truth["effects"] = ["foundation_coupling"]
    with open(os.path.join(path, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
        f.write("\n")


def main():
    for k, (name, (speeds, variants)) in enumerate(MACHINES.items()):
        with open(os.path.join(HERE, name + ".toml"), "rb") as f:
            spec = tomllib.load(f)
        resp, coefs = respond(spec, speeds)
        for variant in variants:
            rng = np.random.default_rng(1997 + 31 * k)
            path = os.path.join(HERE, f"{name}-{variant}")
            write_run(path, spec, speeds, resp, coefs, variant, rng)
            print(f"{path}: {len(speeds)} speeds x {len(spec['bearings'])} bearings")


if __name__ == "__main__":
    main()
