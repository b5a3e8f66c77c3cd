#!/usr/bin/env python3
"""The Cramér–Rao bound of one pedestal from its true phasors, computed apart
from plinth (numpy), and the identify ± and errors of noise redraws against it
(docs/unseen-six.md "Session 46 (lowsnr17)").

Usage: python3 scripts/fisher_true_phasors.py EXACT BEARING [IDENTIFY.json...]
       python3 scripts/fisher_true_phasors.py --diagonal EXACT BEARING

EXACT: a noiseless run directory with noise columns and truth.json (e.g.
scripts/ross_unseen_redraw.py's OUT/CASE-exact). Per speed the complex
equation e = H(θ)·ped − K*·rel at the truth θ, its noise covariance
C = H·D_ped·Hᴴ + K*·D_rel·K*ᴴ from the columns (sd² per complex phasor),
A = ∂e/∂θ; M = Σ 2·Re(AᴴC⁻¹A) is the true phasors' information and
N = Σ_c sd_c²·2·Re(G_cᴴC⁻¹G_c) what the noise of `ped` adds to the
information of measured phasors (G_c: A of a unit phasor on channel c).
Prints the noise share (largest eigenvalue of (M + N)⁻¹N) and the bound
√diag M⁻¹; with `plinth identify --json` outputs of noise redraws of the same
response, the RMS of their printed ± and of their errors over the bound.

--diagonal: the covariance of a fit weighted by one variance per real
equation (the diagonal of the real 4×4 Σ per speed, as `diagnose`'s search
weights it) over the bound, √ of the diagonal: its floor (JᵀW_dJ)⁻¹ and its
true (sandwich) covariance (JᵀW_dJ)⁻¹JᵀW_dΣW_dJ(JᵀW_dJ)⁻¹.
"""
import csv
import json
import math
import os
import sys

import numpy as np

PARAMS = ("k_y", "k_z", "m", "c_y", "c_z")


def rows(ped, w):
    """A = ∂e/∂(k_y, k_z, m, c_y, c_z) (2×5 complex) for pedestal phasors `ped`."""
    a = np.zeros((2, 5), complex)
    a[0, 0], a[1, 1] = ped[0], ped[1]
    a[:, 2] = -w * w * ped
    a[0, 3], a[1, 4] = 1j * w * ped[0], 1j * w * ped[1]
    return a


def real_form(c):
    """The real 2m×2n form of a complex m×n matrix on (re, im) pairs."""
    m, n = c.shape
    r = np.zeros((2 * m, 2 * n))
    for i in range(m):
        for j in range(n):
            z = c[i, j]
            r[2 * i:2 * i + 2, 2 * j:2 * j + 2] = [[z.real, -z.imag], [z.imag, z.real]]
    return r


def information(run, bearing):
    """(M, N, θ, D_floor, D_meat) of `bearing` in the run directory `run`:
    D_floor = Σ AᵀW_dA and D_meat = Σ AᵀW_dΣW_dA of the diagonal weighting."""
    with open(os.path.join(run, "truth.json")) as f:
        t = {p["bearing"]: p for p in json.load(f)["pedestals"]}[bearing]
    th = np.array([t[k] for k in PARAMS])
    with open(os.path.join(run, "bearings.csv")) as f:
        table = {float(r["speed_hz"]): r for r in csv.DictReader(f) if r["bearing"] == bearing}
    m_info, n_info = np.zeros((5, 5)), np.zeros((5, 5))
    d_floor, d_meat = np.zeros((5, 5)), np.zeros((5, 5))
    with open(os.path.join(run, "measurements.csv")) as f:
        for r in csv.DictReader(f):
            if r["bearing"] != bearing:
                continue
            hz = float(r["speed_hz"])
            w, b = 2 * math.pi * hz, table[hz]
            phasor = lambda c: complex(float(r[c + "_re"]), float(r[c + "_im"]))  # noqa: E731
            ped = np.array([phasor("ped_y"), phasor("ped_z")])
            sd_rel = np.array([float(r["rel_y_sd"]), float(r["rel_z_sd"])])
            sd_ped = np.array([float(r["ped_y_sd"]), float(r["ped_z_sd"])])
            k = np.array([[float(b[f"k{i}{j}"]) + 1j * w * float(b[f"c{i}{j}"]) for j in "yz"] for i in "yz"])
            h = np.diag([th[0] - w * w * th[2] + 1j * w * th[3], th[1] - w * w * th[2] + 1j * w * th[4]])
            c = h @ np.diag(sd_ped ** 2) @ h.conj().T + k @ np.diag(sd_rel ** 2) @ k.conj().T
            c_inv = np.linalg.inv(c)
            a = rows(ped, w)
            m_info += 2 * np.real(a.conj().T @ c_inv @ a)
            for ch in (0, 1):
                g = rows(np.eye(2)[ch].astype(complex), w)
                n_info += sd_ped[ch] ** 2 * 2 * np.real(g.conj().T @ c_inv @ g)
            # Real form: e = (Re e_y, Im e_y, Re e_z, Im e_z), noise (rel_y, rel_z, ped_y, ped_z).
            b_real = np.hstack([real_form(-k), real_form(h)])
            sigma = b_real @ np.diag(np.repeat(np.concatenate([sd_rel, sd_ped]) ** 2 / 2, 2)) @ b_real.T
            a_real = np.zeros((4, 5))
            a_real[0::2], a_real[1::2] = a.real, a.imag
            w_d = np.diag(1.0 / np.diag(sigma))
            d_floor += a_real.T @ w_d @ a_real
            d_meat += a_real.T @ w_d @ sigma @ w_d @ a_real
    return m_info, n_info, th, d_floor, d_meat


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    diagonal = sys.argv[1] == "--diagonal"
    args = sys.argv[2:] if diagonal else sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    run, bearing, outputs = args[0], args[1], args[2:]
    m_info, n_info, th, d_floor, d_meat = information(run, bearing)
    share = float(max(np.real(np.linalg.eigvals(np.linalg.solve(m_info + n_info, n_info)))))
    bound = np.sqrt(np.diag(np.linalg.inv(m_info)))
    print(f"{bearing}: noise share {share:.4f}; bound " + " ".join(f"{k} {b:.4g}" for k, b in zip(PARAMS, bound)))
    if diagonal:
        inv = np.linalg.inv(d_floor)
        for name, cov in (("floor", inv), ("true", inv @ d_meat @ inv)):
            ratio = np.sqrt(np.diag(cov)) / bound
            print(f"  diagonal weights, {name} / bound: " + " ".join(f"{k} {r:.3f}" for k, r in zip(PARAMS, ratio)))
    if not outputs:
        return
    fits = []
    for o in outputs:
        with open(o) as f:
            fits.append({p["bearing"]: p for p in json.load(f)["pedestals"]}[bearing])
    for i, k in enumerate(PARAMS):
        v = np.array([p[k] for p in fits])
        se = np.array([p["std_err"][k] for p in fits])
        print(f"  {k}: RMS printed ± / bound {math.sqrt(np.mean(se ** 2)) / bound[i]:.3f}, "
              f"RMS error / bound {math.sqrt(np.mean((v - th[i]) ** 2)) / bound[i]:.3f} ({len(v)} fits)")


if __name__ == "__main__":
    main()
