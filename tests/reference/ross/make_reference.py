#!/usr/bin/env python3
"""Reference unbalance responses from ROSS 2.3.0 for Plinth's simulator.

Usage:  python3 tests/reference/ross/make_reference.py [machine-c ...]  (writes *.json here)
        python3 tests/reference/ross/make_reference.py --time   (ROSS timing only)

Builds the same machines as Plinth's machine files (machine-a.toml,
machine-b.toml, read with tomllib) in ROSS: Timoshenko shaft elements with
shear, rotary inertia and gyroscopics; DiskElement; each bearing a
BearingElement from the shaft node to a PointMass (n_link), and the pedestal
a second BearingElement from the point mass to the ground, or, when the
bearing names a `base` (machine-c.toml), to that base: each [[base]] is a
PointMass (mx, my) with its own BearingElement to the ground. A bearing's
`sub_base` (machine-d.toml) is built the same way: a PointMass under that
pedestal only, the pedestal's BearingElement from pedestal to sub-base and the
sub-base's own BearingElement to the ground.

Axes. Plinth: x along the rotor, y vertical, z horizontal, spin about +x,
forward whirl y -> z, unbalance angle from +y towards +z. ROSS: z along the
rotor, spin about +z, forward whirl x -> y, unbalance angle from +x towards
+y. The map Plinth (y, z) -> ROSS (x, y) is a proper rotation (x_P -> z_R,
y_P -> x_R, z_P -> y_R), so spin, whirl, gyroscopics and the unbalance angle
carry over unchanged: kyy -> kxx, kyz -> kxy, kzy -> kyx, kzz -> kyy, and the
response phasors map one to one (both use x(t) = Re{X e^{i Omega t}}).
Gravity plays no part in the linear response; oil-film coefficients are
computed here (short-bearing theory, the same closed form as
host/src/sim/oil_film.rs, mapped to (y, z)) and passed to ROSS as speed tables
at exactly the simulated speeds.
"""
import json
import math
import os
import sys
import time
import tomllib
import warnings

import numpy as np

warnings.filterwarnings("ignore")
HERE = os.path.dirname(os.path.abspath(__file__))
G0 = 9.80665


def material_of(m):
    E = m["young_modulus"]
    if "shear_modulus" in m:
        nu = E / (2 * m["shear_modulus"]) - 1
    else:
        nu = m["poisson_ratio"]
    return E, nu, m["density"]


def shaft_elements(spec):
    """(L, od, id, E, nu, rho) per element and node positions."""
    els, x = [], [spec["shaft"].get("start", 0.0)]
    default = spec["shaft"].get("material")
    for sec in spec["shaft"]["sections"]:
        E, nu, rho = material_of(sec.get("material", default))
        n = sec.get("elements", 1)
        for _ in range(n):
            L = sec["length"] / n
            els.append((L, sec["outer_diameter"], sec.get("inner_diameter", 0.0), E, nu, rho))
            x.append(x[-1] + L)
    return els, x


def node_of(item, x):
    if "node" in item:
        return item["node"]
    return int(np.argmin([abs(p - item["position"]) for p in x]))


def disks_of(spec, x):
    out = []
    for d in spec.get("disks", []):
        if "mass" in d:
            m, ip, idm = d["mass"], d["polar_inertia"], d["diametral_inertia"]
        else:
            w, do, di, rho = d["width"], d["outer_diameter"], d.get("inner_diameter", 0.0), d["density"]
            m = rho * math.pi * w * (do**2 - di**2) / 4
            ip = m * (do**2 + di**2) / 8
            idm = ip / 2 + m * w**2 / 12
        out.append((node_of(d, x), m, ip, idm, d.get("unbalance", 0.0), d.get("unbalance_angle", 0.0)))
    return out


def static_loads(spec, els, x, disks):
    """Lever rule for two bearings (statically determinate)."""
    bx = [x[node_of(b, x)] for b in spec["bearings"]]
    assert len(bx) == 2
    forces = []  # (position, downward weight)
    for i, (L, od, idd, E, nu, rho) in enumerate(els):
        forces.append((x[i] + L / 2, rho * math.pi * (od**2 - idd**2) / 4 * L * G0))
    for (n, m, *_rest) in disks:
        forces.append((x[n], m * G0))
    W = sum(f for _, f in forces)
    M1 = sum(f * (p - bx[0]) for p, f in forces)
    r2 = M1 / (bx[1] - bx[0])
    return [W - r2, r2]


def ocvirk(of, W, speed_hz):
    """Short-bearing coefficients (K [N/m], C [N s/m]) in Plinth's (y, z)."""
    Om = 2 * math.pi * speed_hz
    Ss = of["diameter"] * Om * of["viscosity"] * of["length"] ** 3 / (8 * W * of["clearance"] ** 2)
    f = lambda e: e * math.sqrt(16 * e * e + math.pi**2 * (1 - e * e)) / (1 - e * e) ** 2 - 1 / Ss
    lo, hi = 0.0, 1.0 - 1e-15
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(mid) < 0:
            lo = mid
        else:
            hi = mid
    e = 0.5 * (lo + hi)
    pi2 = math.pi**2
    h0 = 1 / (pi2 * (1 - e * e) + 16 * e * e) ** 1.5
    s = math.sqrt(1 - e * e)
    a = [[h0 * 4 * (pi2 * (2 - e * e) + 16 * e * e),
          h0 * math.pi * (pi2 * (1 - e * e) ** 2 - 16 * e**4) / (e * s)],
         [-h0 * math.pi * (pi2 * (1 - e * e) * (1 + 2 * e * e) + 32 * e * e * (1 + e * e)) / (e * s),
          h0 * 4 * (pi2 * (1 + 2 * e * e) + 32 * e * e * (1 + e * e) / (1 - e * e))]]
    buv = -h0 * 8 * (pi2 * (1 + 2 * e * e) - 16 * e * e)
    b = [[h0 * 2 * math.pi * s * (pi2 * (1 + 2 * e * e) - 16 * e * e) / e, buv],
         [buv, h0 * 2 * math.pi * (pi2 * (1 - e * e) ** 2 + 48 * e * e) / (e * s)]]
    ks, cs = W / of["clearance"], W / (of["clearance"] * Om)
    # Friswell's frame: u horizontal, v along the load line. In (y, z) with
    # rotation y -> z: Kyy = avv, Kyz = -avu, Kzy = -auv, Kzz = auu (C alike).
    K = [[ks * a[1][1], -ks * a[1][0]], [-ks * a[0][1], ks * a[0][0]]]
    C = [[cs * b[1][1], -cs * b[1][0]], [-cs * b[0][1], cs * b[0][0]]]
    return K, C


def build(spec, speeds_hz):
    import ross as rs

    els, x = shaft_elements(spec)
    shaft = []
    for (L, od, idd, E, nu, rho) in els:
        mat = rs.Material(name=f"m{E:.0f}_{nu}_{rho}".replace(".", "_"), rho=rho, E=E, Poisson=nu)
        shaft.append(rs.ShaftElement(L=L, idl=idd, odl=od, material=mat,
                                     shear_effects=True, rotary_inertia=True, gyroscopic=True))
    disks = disks_of(spec, x)
    disk_elements = [rs.DiskElement(n=n, m=m, Id=idm, Ip=ip, tag=f"disk{k}") for k, (n, m, ip, idm, _u, _a) in enumerate(disks)]
    unb = [(n, u, a) for (n, _m, _ip, _id, u, a) in disks if u > 0]
    unb += [(node_of(u, x), u["magnitude"], u.get("angle", 0.0)) for u in spec.get("unbalance", [])]
    loads = None
    n_nodes = len(x)
    bearings, masses, coef_record = [], [], {}
    w = 2 * math.pi * np.asarray(speeds_hz)
    for i, b in enumerate(spec["bearings"]):
        n = node_of(b, x)
        if "oil_film" in b:
            if loads is None:
                loads = static_loads(spec, els, x, disks)
            of = b["oil_film"]
            W = of["load"] if isinstance(of["load"], float) else loads[i]
            K, C = zip(*[ocvirk(of, W, s) for s in speeds_hz])
            kyy = [k[0][0] for k in K]; kyz = [k[0][1] for k in K]; kzy = [k[1][0] for k in K]; kzz = [k[1][1] for k in K]
            cyy = [c[0][0] for c in C]; cyz = [c[0][1] for c in C]; czy = [c[1][0] for c in C]; czz = [c[1][1] for c in C]
        else:
            row = b["coefficients"][0]
            g = lambda k: [row.get(k, 0.0)] * len(speeds_hz)
            kyy, kyz, kzy, kzz = g("kyy"), g("kyz"), g("kzy"), g("kzz")
            cyy, cyz, czy, czz = g("cyy"), g("cyz"), g("czy"), g("czz")
        coef_record[b["name"]] = {"kyy": kyy, "kyz": kyz, "kzy": kzy, "kzz": kzz,
                                  "cyy": cyy, "cyz": cyz, "czy": czy, "czz": czz}
        p = b["pedestal"]
        pn = n_nodes + len(masses)
        # Plinth (y, z) -> ROSS (x, y).
        bearings.append(rs.BearingElement(n=n, n_link=pn, frequency=w,
                                          kxx=kyy, kxy=kyz, kyx=kzy, kyy=kzz,
                                          cxx=cyy, cxy=cyz, cyx=czy, cyy=czz, tag=f"brg_{b['name']}"))
        masses.append(rs.PointMass(n=pn, m=p["m"], tag=f"ped_{b['name']}"))
        bearings.append(rs.BearingElement(n=pn, kxx=p["k_y"], kyy=p["k_z"],
                                          cxx=p.get("c_y", 0.0), cyy=p.get("c_z", 0.0),
                                          tag=f"ground_{b['name']}"))
    base_node = {}
    for j, base in enumerate(spec.get("base", [])):
        bn = n_nodes + len(spec["bearings"]) + j
        base_node[base["name"]] = bn
        my_, mz_ = (base["m"], base["m"]) if "m" in base else (base["m_y"], base["m_z"])
        assert base.get("eta", 0.0) == 0.0, "ROSS has no hysteretic base damping"
        # mz: ROSS's axial DOF of the point mass (no axial spring anywhere, so
        # it needs a mass to keep the matrix regular; it does not couple).
        masses.append(rs.PointMass(n=bn, mx=my_, my=mz_, mz=0.5 * (my_ + mz_),
                                   tag=f"base_{base['name']}"))
        bearings.append(rs.BearingElement(n=bn, kxx=base["k_y"], kyy=base["k_z"],
                                          cxx=base.get("c_y", 0.0), cyy=base.get("c_z", 0.0),
                                          tag=f"basegr_{base['name']}"))
    for i, b in enumerate(spec["bearings"]):
        if "base" in b:
            # The pedestal acts between pedestal and base, not ground.
            el = [e for e in bearings if e.tag == f"ground_{b['name']}"][0]
            k = bearings.index(el)
            p = b["pedestal"]
            bearings[k] = rs.BearingElement(n=n_nodes + i, n_link=base_node[b["base"]],
                                            kxx=p["k_y"], kyy=p["k_z"],
                                            cxx=p.get("c_y", 0.0), cyy=p.get("c_z", 0.0),
                                            tag=f"pedbase_{b['name']}")
    n_sub = 0
    for i, b in enumerate(spec["bearings"]):
        if "sub_base" in b:
            sb = b["sub_base"]
            sn = n_nodes + len(spec["bearings"]) + len(spec.get("base", [])) + n_sub
            n_sub += 1
            my_, mz_ = (sb["m"], sb["m"]) if "m" in sb else (sb["m_y"], sb["m_z"])
            assert sb.get("eta", 0.0) == 0.0, "ROSS has no hysteretic damping here"
            masses.append(rs.PointMass(n=sn, mx=my_, my=mz_, mz=0.5 * (my_ + mz_),
                                       tag=f"sub_{b['name']}"))
            bearings.append(rs.BearingElement(n=sn, kxx=sb["k_y"], kyy=sb["k_z"],
                                              cxx=sb.get("c_y", 0.0), cyy=sb.get("c_z", 0.0),
                                              tag=f"subgr_{b['name']}"))
            el = [e for e in bearings if e.tag == f"ground_{b['name']}"][0]
            k = bearings.index(el)
            p = b["pedestal"]
            bearings[k] = rs.BearingElement(n=n_nodes + i, n_link=sn,
                                            kxx=p["k_y"], kyy=p["k_z"],
                                            cxx=p.get("c_y", 0.0), cyy=p.get("c_z", 0.0),
                                            tag=f"pedsub_{b['name']}")
    rotor = rs.Rotor(shaft, disk_elements, bearings, point_mass_elements=masses)
    return rotor, x, unb, coef_record


def run(name):
    with open(os.path.join(HERE, name + ".toml"), "rb") as f:
        spec = tomllib.load(f)
    speeds = [float(s) for s in range(5, 201)]
    rotor, x, unb, coefs = build(spec, speeds)
    w = 2 * math.pi * np.asarray(speeds)
    t0 = time.perf_counter()
    resp = rotor.run_unbalance_response([u[0] for u in unb], [u[1] for u in unb],
                                        [math.radians(u[2]) for u in unb], frequency=w)
    elapsed = time.perf_counter() - t0
    X = resp.forced_resp  # (ndof, nspeeds)
    ndof_node = rotor.number_dof
    out = {"machine": name + ".toml", "ross_version": __import__("ross").__version__,
           "speeds_hz": speeds, "bearings": {}, "coefficients": coefs,
           "ross_seconds_per_speed": elapsed / len(speeds), "ross_ndof": int(rotor.ndof)}
    n_nodes = len(x)
    for i, b in enumerate(spec["bearings"]):
        n = node_of(b, x)
        pn = n_nodes + i
        sx = X[ndof_node * n + 0]; sy = X[ndof_node * n + 1]
        gi = {e.tag: e for e in rotor.point_mass_elements}[f"ped_{b['name']}"].dof_global_index
        px = X[gi[f"x_{pn}"]]; py = X[gi[f"y_{pn}"]]
        rel_y, rel_z, ped_y, ped_z = sx - px, sy - py, px, py
        out["bearings"][b["name"]] = {
            k: {"re": list(map(float, v.real)), "im": list(map(float, v.imag))}
            for k, v in (("rel_y", rel_y), ("rel_z", rel_z), ("ped_y", ped_y), ("ped_z", ped_z))}
    pm = {e.tag: e for e in rotor.point_mass_elements}
    for j, base in enumerate(spec.get("base", [])):
        bn = n_nodes + len(spec["bearings"]) + j
        gi = pm[f"base_{base['name']}"].dof_global_index
        by = X[gi[f"x_{bn}"]]; bz = X[gi[f"y_{bn}"]]
        out.setdefault("bases", {})[base["name"]] = {
            k: {"re": list(map(float, v.real)), "im": list(map(float, v.imag))}
            for k, v in (("y", by), ("z", bz))}
    for b in spec["bearings"]:
        if "sub_base" in b:
            e = pm[f"sub_{b['name']}"]
            gi = e.dof_global_index
            sy = X[gi[f"x_{e.n}"]]; sz = X[gi[f"y_{e.n}"]]
            out.setdefault("sub_bases", {})[b["name"]] = {
                k: {"re": list(map(float, v.real)), "im": list(map(float, v.imag))}
                for k, v in (("y", sy), ("z", sz))}
    return out, elapsed, len(speeds), rotor.ndof


def main():
    if "--time" in sys.argv:
        # Timing on the benchmark model (host/benches/unbalance_sweep.rs):
        # machine-a, 1000 speeds.
        with open(os.path.join(HERE, "machine-a.toml"), "rb") as f:
            spec = tomllib.load(f)
        speeds = list(np.linspace(5.0, 200.0, 1000))
        rotor, x, unb, _ = build(spec, speeds)
        w = 2 * math.pi * np.asarray(speeds)
        t0 = time.perf_counter()
        rotor.run_unbalance_response([u[0] for u in unb], [u[1] for u in unb],
                                     [math.radians(u[2]) for u in unb], frequency=w)
        el = time.perf_counter() - t0
        print(f"ROSS {rs_version()}: machine-a, {rotor.ndof} DOF (ROSS counts 6 per node), "
              f"1000 speeds: {el:.3f} s total, {el / 1000 * 1e3:.3f} ms per speed")
        return
    names = [a for a in sys.argv[1:] if not a.startswith("-")] or ["machine-a", "machine-b", "machine-c", "machine-d"]
    for name in names:
        out, el, n, ndof = run(name)
        with open(os.path.join(HERE, name + ".json"), "w") as f:
            json.dump(out, f)
        print(f"{name}: {n} speeds, ROSS {ndof} DOF, {el / n * 1e3:.2f} ms per speed")


def rs_version():
    import ross
    return ross.__version__


if __name__ == "__main__":
    main()
