#!/usr/bin/env python3
"""Cramér–Rao bounds of a pedestal on its own sub-base, from one run's speeds,
bearing table and noise columns (docs/diagnose-sub-base.md, "pedestal_sub_base above
the range").

Usage: python3 scripts/crlb_sub_base.py RUN BEARING m_p M_s k_py k_pz K_sy K_sz c_py c_pz C_sy C_sz

Per direction d the measured pedestal (mass m_p, spring z_p = k_pd + iΩc_pd)
on its sub-base (mass M_s, spring z_s = K_sd + iΩC_sd to ground) has the
dynamic stiffness Z_d(Ω) = z_p − Ω²m_p − z_p²/(z_p + z_s − Ω²M_s); the two
masses are one number each for y and z (each is one body). The equation of
each speed and direction is e = Z_d·X_d − F_d with F = K*·rel (the bearing
force from the run's table) and X_d = F_d/Z_d (the model's motion); its
variance |Z_d|²σ²(X_d) + Σ_c |K*_dc|²σ²(rel_c), half on each real part (the
noise columns' complex sd, formats.md). Prints the bounds of every
parameter relative to its value (the information in the logarithms),
with the dampings free, and with subsets held known. Independent of
Plinth's code: numpy only.
"""
import csv
import sys

import numpy as np

NAMES = ["m_p", "M_s", "k_py", "k_pz", "K_sy", "K_sz", "c_py", "c_pz", "C_sy", "C_sz"]


def rows(run, bearing):
    meas = [r for r in csv.DictReader(open(f"{run}/measurements.csv")) if r["bearing"] == bearing]
    table = {float(r["speed_hz"]): r for r in csv.DictReader(open(f"{run}/bearings.csv"))
             if r["bearing"] == bearing}
    out = []
    for r in meas:
        f = float(r["speed_hz"])
        t = table[f]
        w = 2 * np.pi * f
        g = lambda k: float(t[k])
        kstar = (np.array([[g("kyy"), g("kyz")], [g("kzy"), g("kzz")]])
                 + 1j * w * np.array([[g("cyy"), g("cyz")], [g("czy"), g("czz")]]))
        rel = np.array([float(r["rel_y_re"]) + 1j * float(r["rel_y_im"]),
                        float(r["rel_z_re"]) + 1j * float(r["rel_z_im"])])
        sr = np.array([float(r["rel_y_sd"]), float(r["rel_z_sd"])])
        sp = np.array([float(r["ped_y_sd"]), float(r["ped_z_sd"])])
        out.append((w, kstar, rel, sr, sp))
    return out


def z(p, d, w):
    zp = p[2 + d] + 1j * w * p[6 + d]
    zs = p[4 + d] + 1j * w * p[8 + d]
    return zp - w * w * p[0] - zp * zp / (zp + zs - w * w * p[1])


def fisher(data, p):
    info = np.zeros((len(p), len(p)))
    for w, kstar, rel, sr, sp in data:
        force = kstar @ rel
        for d in range(2):
            zd = z(p, d, w)
            var = (abs(zd) ** 2 * sp[d] ** 2 + sum(abs(kstar[d, c]) ** 2 * sr[c] ** 2 for c in range(2))) / 2
            x = force[d] / zd
            g = []
            for i in range(len(p)):
                q = p.copy()
                h = 1e-6 * p[i]
                q[i] += h
                g.append((z(q, d, w) - zd) / h * p[i] * x)
            g = np.array(g)
            info += np.real(np.outer(g.conj(), g)) / var
    return info


def main():
    if len(sys.argv) != 13:
        sys.exit(__doc__)
    run, bearing = sys.argv[1], sys.argv[2]
    p = np.array([float(v) for v in sys.argv[3:]])
    info = fisher(rows(run, bearing), p)
    for label, idx in [("all ten free", range(10)),
                       ("pedestal damping c_p known", [0, 1, 2, 3, 4, 5, 8, 9]),
                       ("sub-base damping C_s known", [0, 1, 2, 3, 4, 5, 6, 7]),
                       ("every damping known", range(6)),
                       ("both masses known", range(2, 10))]:
        idx = list(idx)
        cov = np.linalg.inv(info[np.ix_(idx, idx)])
        print(f"{label}: " + ", ".join(
            f"{NAMES[i]} ±{100 * np.sqrt(cov[j, j]):.1f} %" for j, i in enumerate(idx)))


if __name__ == "__main__":
    main()
