#!/usr/bin/env python3
"""Run directories of a machine Plinth was never tuned to, made by ROSS 2.3.0.

Usage:
  python3 scripts/ross_unseen.py OUT CASE SEED...  run directories OUT/CASE-SEED
  python3 scripts/ross_unseen.py --cases            the case names
  python3 scripts/ross_unseen.py --repo             the stored runs
        (tests/data/ross-unseen/<case>/, seed 1 of REPO_CASES)

Needs ROSS 2.3.0 (`pip install ross-rotordynamics==2.3.0 "plotly<6"`).
Deterministic: the seed fixes the noise, the flipped speeds and (3-digit
cases) the speed grid.

The machine is tests/data/ross-unseen/unseen-four.toml (read with tomllib):
four bearings, an overhung disk, two tabulated and two oil-film bearings,
pedestals of 70-240 kg, B4 undamped. It is built in ROSS here, not by
Plinth: Timoshenko shaft elements (shear, rotary inertia, gyroscopics),
DiskElements, each bearing a BearingElement from the shaft node to a
PointMass (n_link, the pedestal), the pedestal a BearingElement to the
ground, to a shared base PointMass, or to its own sub-base PointMass.
Oil-film coefficients come from the short-bearing closed form of
tests/reference/ross/make_reference.py (`ocvirk`, Python, not Plinth's
code) at exactly the run's speeds. The response is ROSS's
run_unbalance_response; the run directory is written here following
docs/formats.md directly (rel = rotor - pedestal, ped absolute, y vertical,
z horizontal, q(t) = Re{Q e^{iWt}}; the axis map Plinth (y, z) -> ROSS
(x, y) is make_reference.py's, a proper rotation).

Cases (what the truth is; `expect` in truth.json's effect_details):
  clean-w1     1 % white noise (of each channel's RMS), 7 digits, no columns
  clean-w1c    the same with the *_sd noise columns
  clean-d3     no noise, 3 significant digits, speed grid shifted by the seed
  sub-base     B3's pedestal on its own sub-base (180/160 kg, 24/20 MN/m)
  table        B2's true clearance 1/0.85 of the drawn one: bearings.csv is
               computed for a clearance 15 % smaller than the machine's
  cross        pedestal cross-coupling k_yz = k_zy = 0.2 sqrt(k_y k_z) at B4
  runout       a speed-independent runout on B3's rel probes
  flips        three speeds of B1 with every channel negated (keyphasor)
  base-runout  B1 and B2 on a shared 350 kg frame, and runout on B2's probes
Effect cases carry 1 % white noise with the *_sd columns; EFFECT-d3 is the
same effect without noise at 3 significant digits (grid shifted by the seed).
"""
import json
import math
import os
import sys
import tomllib
import warnings

import numpy as np

warnings.filterwarnings("ignore")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "reference", "ross"))
from make_reference import disks_of, node_of, ocvirk, shaft_elements  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data", "ross-unseen")
MACHINE = os.path.join(DATA, "unseen-four.toml")
CHANNELS = ("rel_y", "rel_z", "ped_y", "ped_z")
NOISE = 0.01
STEP = 1.25  # Hz
FIRST, LAST = 6.0, 126.0
SUB_BASE = {"bearing": "B3", "m_y": 180.0, "m_z": 160.0, "k_y": 2.4e7, "k_z": 2.0e7,
            "c_y": 2500.0, "c_z": 2000.0}
FRAME = {"name": "frame", "bearings": ["B1", "B2"], "m_y": 350.0, "m_z": 350.0,
         "k_y": 1.6e7, "k_z": 2.2e7, "c_y": 3000.0, "c_z": 2500.0}
WORN = ("B2", 1.0 / 0.85)   # bearing, true clearance / drawn clearance
CROSS = ("B4", 0.2)         # bearing, k_yz / sqrt(k_y k_z)
RUNOUT_SIZE = 0.2           # of the median |rel| of the bearing
EFFECTS = ("sub-base", "table", "cross", "runout", "flips", "base-runout")
CASES = ("clean-w1", "clean-w1c", "clean-d3") + EFFECTS + tuple(e + "-d3" for e in EFFECTS)

# The runs kept in the repository (tests/tests/unseen_machine.rs), seed 1.
REPO_CASES = ("clean-w1c", "clean-d3", "sub-base", "sub-base-d3", "table", "cross", "runout",
              "flips", "base-runout-d3")


def kind(case):
    """(effect, noise) of a case: noise "w1" (1 % white), "w1c" (and the
    *_sd columns) or "d3" (none, 3 digits)."""
    if case.startswith("clean-"):
        return "clean", case[len("clean-"):]
    if case.endswith("-d3"):
        return case[:-3], "d3"
    return case, "w1c"


def speeds_of(case, seed):
    shift = 0.137 * (seed - 1) if kind(case)[1] == "d3" else 0.0
    n = int(round((LAST - FIRST) / STEP)) + 1
    return np.round(FIRST + shift + STEP * np.arange(n), 4)


def table_row(b, s):
    """Tabulated coefficients at speed s, linear in speed between rows."""
    rows = b["coefficients"]
    keys = ("kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz")
    sp = [r["speed_hz"] for r in rows]
    return {k: float(np.interp(s, sp, [r.get(k, 0.0) for r in rows])) for k in keys}


def film_row(of, s, clearance):
    K, C = ocvirk(dict(of, clearance=clearance), of["load"], s)
    return {"kyy": K[0][0], "kyz": K[0][1], "kzy": K[1][0], "kzz": K[1][1],
            "cyy": C[0][0], "cyz": C[0][1], "czy": C[1][0], "czz": C[1][1]}


def coefficients(spec, speeds, worn):
    """(true, written) coefficients per bearing: lists of dicts per speed."""
    true, written = {}, {}
    for b in spec["bearings"]:
        if "oil_film" in b:
            of = b["oil_film"]
            factor = WORN[1] if worn and b["name"] == WORN[0] else 1.0
            true[b["name"]] = [film_row(of, s, of["clearance"] * factor) for s in speeds]
            written[b["name"]] = [film_row(of, s, of["clearance"]) for s in speeds]
        else:
            true[b["name"]] = written[b["name"]] = [table_row(b, s) for s in speeds]
    return true, written


def respond(spec, speeds, case):
    """ROSS's rel and ped phasors per bearing (Plinth's axes) and the tables."""
    import ross as rs

    els, x = shaft_elements(spec)
    shaft = []
    for (L, od, idd, E, nu, rho) in els:
        mat = rs.Material(name=f"m{E:.0f}_{nu}_{rho}".replace(".", "_"), rho=rho, E=E, Poisson=nu)
        shaft.append(rs.ShaftElement(L=L, idl=idd, odl=od, material=mat, shear_effects=True,
                                     rotary_inertia=True, gyroscopic=True))
    disks = disks_of(spec, x)
    disk_elements = [rs.DiskElement(n=n, m=m, Id=idm, Ip=ip, tag=f"disk{k}")
                     for k, (n, m, ip, idm, _u, _a) in enumerate(disks)]
    unb = [(n, u, a) for (n, _m, _ip, _id, u, a) in disks if u > 0]
    true, written = coefficients(spec, speeds, case == "table")
    w = 2 * math.pi * np.asarray(speeds)
    nn = len(x)
    names = [b["name"] for b in spec["bearings"]]
    extra = nn + len(names)  # the next free node number after the pedestals
    base_node = sub_node = None
    if case == "base-runout":
        base_node, extra = extra, extra + 1
    if case == "sub-base":
        sub_node, extra = extra, extra + 1
    elements, masses = [], []
    for i, b in enumerate(spec["bearings"]):
        c = true[b["name"]]
        col = lambda k: [r[k] for r in c]  # noqa: E731
        pn = nn + i
        elements.append(rs.BearingElement(
            n=node_of(b, x), n_link=pn, frequency=w, kxx=col("kyy"), kxy=col("kyz"),
            kyx=col("kzy"), kyy=col("kzz"), cxx=col("cyy"), cxy=col("cyz"), cyx=col("czy"),
            cyy=col("czz"), tag=f"brg_{b['name']}"))
        p = b["pedestal"]
        masses.append(rs.PointMass(n=pn, m=p["m"], tag=f"ped_{b['name']}"))
        kc = CROSS[1] * math.sqrt(p["k_y"] * p["k_z"]) if case == "cross" and b["name"] == CROSS[0] else 0.0
        link = None
        if base_node is not None and b["name"] in FRAME["bearings"]:
            link = base_node
        if sub_node is not None and b["name"] == SUB_BASE["bearing"]:
            link = sub_node
        kw = dict(kxx=p["k_y"], kyy=p["k_z"], kxy=kc, kyx=kc, cxx=p.get("c_y", 0.0),
                  cyy=p.get("c_z", 0.0), tag=f"ground_{b['name']}")
        if link is not None:
            kw["n_link"] = link
        elements.append(rs.BearingElement(n=pn, **kw))
    for node, body in ((base_node, FRAME), (sub_node, SUB_BASE)):
        if node is None:
            continue
        # mz: ROSS's axial DOF of the point mass (nothing couples to it).
        masses.append(rs.PointMass(n=node, mx=body["m_y"], my=body["m_z"],
                                   mz=0.5 * (body["m_y"] + body["m_z"]), tag=f"body{node}"))
        elements.append(rs.BearingElement(n=node, kxx=body["k_y"], kyy=body["k_z"],
                                          cxx=body["c_y"], cyy=body["c_z"], tag=f"bodygr{node}"))
    rotor = rs.Rotor(shaft, disk_elements, elements, point_mass_elements=masses)
    resp = rotor.run_unbalance_response([u[0] for u in unb], [u[1] for u in unb],
                                        [math.radians(u[2]) for u in unb], frequency=w)
    X = resp.forced_resp
    nd = rotor.number_dof
    pm = {e.tag: e for e in rotor.point_mass_elements}
    out = {}
    for i, b in enumerate(spec["bearings"]):
        n, pn = node_of(b, x), nn + i
        gi = pm[f"ped_{b['name']}"].dof_global_index
        py, pz = X[gi[f"x_{pn}"]], X[gi[f"y_{pn}"]]
        sy, sz = X[nd * n + 0], X[nd * n + 1]
        out[b["name"]] = {"rel_y": sy - py, "rel_z": sz - pz, "ped_y": py, "ped_z": pz}
    return out, written


def add_runout(resp, bearing):
    """A speed-independent vector on both rel probes of `bearing` [m]."""
    a = RUNOUT_SIZE * float(np.median(np.abs(np.concatenate(
        [resp[bearing]["rel_y"], resp[bearing]["rel_z"]]))))
    r_y = a * complex(math.cos(math.radians(110)), math.sin(math.radians(110)))
    r_z = 0.8 * a * complex(math.cos(math.radians(-35)), math.sin(math.radians(-35)))
    resp[bearing]["rel_y"] = resp[bearing]["rel_y"] + r_y
    resp[bearing]["rel_z"] = resp[bearing]["rel_z"] + r_z
    return {"r_y_re": r_y.real, "r_y_im": r_y.imag, "r_z_re": r_z.real, "r_z_im": r_z.imag}


def sig(v, digits):
    return f"{v:.{digits - 1}e}"


_CACHE = {}


def make(out, case, seed):
    """Writes one run directory; returns its truth dict."""
    with open(MACHINE, "rb") as f:
        spec = tomllib.load(f)
    speeds = speeds_of(case, seed)
    effect, noise_kind = kind(case)
    key = (effect, tuple(speeds))
    if key not in _CACHE:  # ROSS's response depends on the effect and grid only
        _CACHE[key] = respond(spec, speeds, effect)
    resp, written = _CACHE[key]
    resp = {b: dict(v) for b, v in resp.items()}
    names = [b["name"] for b in spec["bearings"]]
    details = []
    case_name, case = case, effect
    if case == "runout":
        details.append({"name": "probe_runout", "bearing": "B3", "parameters": add_runout(resp, "B3")})
    if case == "base-runout":
        details.append({"name": "foundation_coupling", "bearing": "B1", "parameters": {}})
        details.append({"name": "probe_runout", "bearing": "B2", "parameters": add_runout(resp, "B2")})
    if case == "sub-base":
        details.append({"name": "pedestal_sub_base", "bearing": "B3",
                        "parameters": {k: v for k, v in SUB_BASE.items() if k != "bearing"}})
    if case == "table":
        details.append({"name": "bearing_coefficients", "bearing": WORN[0],
                        "parameters": {"clearance_ratio": WORN[1]}})
    if case == "cross":
        p = next(b for b in spec["bearings"] if b["name"] == CROSS[0])["pedestal"]
        details.append({"name": "pedestal_cross_coupling", "bearing": CROSS[0],
                        "parameters": {"k_yz": CROSS[1] * math.sqrt(p["k_y"] * p["k_z"])}})
    rng = np.random.default_rng(17_000 + 101 * CASES.index(case_name) + seed)
    noisy = noise_kind != "d3"
    columns = noise_kind == "w1c"
    digits = 7 if noisy else 3
    data, sd = {}, {}
    for b in names:
        for c in CHANNELS:
            v = resp[b][c]
            s = NOISE * math.sqrt(float(np.mean(np.abs(v) ** 2))) if noisy else 0.0
            sd[(b, c)] = s
            noise = (rng.standard_normal(len(v)) + 1j * rng.standard_normal(len(v))) * s / math.sqrt(2)
            data[(b, c)] = v + noise
    flipped = []
    if case == "flips":
        idx = sorted(rng.choice(np.arange(3, len(speeds) - 3), size=3, replace=False).tolist())
        flipped = [float(speeds[i]) for i in idx]
        for c in CHANNELS:
            data[("B1", c)][idx] *= -1
        details.append({"name": "keyphasor_flip", "bearing": "B1",
                        "parameters": {f"speed_{k}_hz": s for k, s in enumerate(flipped)}})
    os.makedirs(out, exist_ok=True)
    fmt = lambda s: f"{s:.6g}"  # noqa: E731
    with open(os.path.join(out, "measurements.csv"), "w") as f:
        head = "speed_hz,bearing," + ",".join(f"{c}_re,{c}_im" for c in CHANNELS)
        if columns:
            head += "," + ",".join(f"{c}_sd" for c in CHANNELS)
        f.write(head + "\n")
        for j, s in enumerate(speeds):
            for b in names:
                row = [fmt(s), b]
                for c in CHANNELS:
                    q = data[(b, c)][j]
                    row += [sig(q.real, digits), sig(q.imag, digits)]
                if columns:
                    row += [sig(sd[(b, c)], 4) for c in CHANNELS]
                f.write(",".join(row) + "\n")
    keys = ("kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz")
    with open(os.path.join(out, "bearings.csv"), "w") as f:
        f.write("speed_hz,bearing," + ",".join(keys) + "\n")
        for j, s in enumerate(speeds):
            for b in names:
                f.write(",".join([fmt(s), b] + [sig(written[b][j][k], 10) for k in keys]) + "\n")
    truth = {"pedestals": [], "effects": [d["name"] for d in details if d["name"] != "keyphasor_flip"],
             "effect_details": details}
    for b in spec["bearings"]:
        p = b["pedestal"]
        truth["pedestals"].append({"bearing": b["name"], "k_y": p["k_y"], "k_z": p["k_z"], "m": p["m"],
                                   "c_y": p.get("c_y", 0.0), "c_z": p.get("c_z", 0.0)})
    if case == "base-runout":
        truth["bases"] = [dict(FRAME, eta=0.0)]
    if case == "sub-base":
        truth["bases"] = [{"name": "B3-sub-base", "bearings": ["B3"], "eta": 0.0,
                           **{k: v for k, v in SUB_BASE.items() if k != "bearing"}}]
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
        f.write("\n")
    return truth


def main():
    args = sys.argv[1:]
    if args == ["--cases"]:
        print("\n".join(CASES))
    elif args == ["--repo"]:
        for case in REPO_CASES:
            make(os.path.join(DATA, case), case, 1)
            print(f"{case}: written")
    elif len(args) >= 3 and args[1] in CASES:
        for seed in args[2:]:
            make(os.path.join(args[0], f"{args[1]}-{seed}"), args[1], int(seed))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
