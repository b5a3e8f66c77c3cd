#!/usr/bin/env python3
"""z = (value − truth)/± of diagnose's final values, per bearing and parameter.

Usage: python3 scripts/final_z.py JSON_DIR RUNS_DIR CASE [CASE...] [--trusted]

JSON_DIR holds `plinth diagnose --json` outputs named
diagnose-CASE-SEED.json; RUNS_DIR the run directories CASE-SEED (with their
truth.json) made by scripts/ross_unseen.py. To keep the outputs of a
`scripts/bench_unseen.py` run, give the bench a wrapper as PLINTH that tees
them (session 43, docs/unseen.md "Session 43 (cross17)"):

    #!/bin/bash
    out=$(/path/to/plinth "$@"); rc=$?
    [ "$1" = diagnose ] && printf '%s' "$out" > "JSON_DIR/$1-$(basename "$2").json"
    printf '%s\n' "$out"; exit $rc

Prints per case, for the final pedestals (`pedestals_after`: k_y, k_z, m,
c_y, c_z where the value has a ± > 0; a held damping has none) and each
named effect's parameters whose truth the run's truth.json gives (k_yz,
a runout's r_*, a sub-base's sub_k_y … as its k_y …): n, mean z with its 95 % interval (t-free: ±1.96 sd/√n), RMS z with
its 95 % interval (χ² with n degrees of freedom, the truth known), and the
values beyond 3 ± (seed, z). The final dampings printed without a ± (held at
zero) whose truth is not zero are listed (seed, bearing, value, truth). Then the pooled tails of k_y, k_z, m: counts
beyond 2 and 3 ± against the normal law's expectation. --trusted: only runs
whose verdict is trusted (the ones "never confidently wrong" is about).
--pooled: every CASE given as one group, each parameter's values at every
bearing together (bearing "all"; a value beyond 3 ± named CASE-SEED BEARING).
"""
import glob
import json
import math
import os
import sys

from scipy.stats import chi2

KEYS = ("k_y", "k_z", "m", "c_y", "c_z")


def runs_of(jd, case):
    """(seed, diagnose JSON) of every saved run of `case`."""
    for f in sorted(glob.glob(os.path.join(jd, f"diagnose-{case}-*.json"))):
        seed = os.path.basename(f)[len(f"diagnose-{case}-"):-5]
        if seed.isdigit():  # not another case whose name extends this one's
            with open(f) as fh:
                yield seed, json.load(fh)


def z_values(d, truth):
    """{(bearing, parameter): z} of one diagnosis against its truth."""
    ped = {p["bearing"]: p for p in truth["pedestals"]}
    out = {}
    for p in d["pedestals_after"]:
        for k in KEYS:
            se = p["std_err"].get(k, 0.0)
            if k in p and se > 0:
                out[(p["bearing"], k)] = (p[k] - ped[p["bearing"]][k]) / se
    eff = {(e["name"], e["bearing"]): e["parameters"] for e in truth["effect_details"]}
    for s in d["steps"]:
        if s.get("dropped"):
            continue
        for q in s.get("parameters", []):
            truth_of = eff.get((s["effect"], s["bearing"]), {})
            # a sub-base's k_y is reported as sub_k_y (the pedestal's own is k_y)
            # and a delay's tau [s] is the truth's tau_s
            tv = truth_of.get(q["name"], truth_of.get(q["name"].removeprefix("sub_"), truth_of.get(q["name"] + "_s")))
            if tv is not None and q["std_err"] > 0:
                out[(s["bearing"], q["name"])] = (q["value"] - tv) / q["std_err"]
    return out


def held_values(d, truth):
    """[(bearing, parameter, value)] of the final pedestals' dampings printed
    without a ± (held at zero) whose truth is not zero: a value the data never
    gave, so no z exists for it."""
    ped = {p["bearing"]: p for p in truth["pedestals"]}
    return [(p["bearing"], k, p.get(k, 0.0)) for p in d["pedestals_after"] for k in ("c_y", "c_z")
            if p["std_err"].get(k, 0.0) <= 0 and ped[p["bearing"]][k] != 0]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) < 3:
        sys.exit(__doc__)
    only_trusted = "--trusted" in sys.argv
    jd, rd, cases = args[0], args[1], args[2:]
    pooled = "--pooled" in sys.argv
    # each case alone, or (--pooled) every case together, every bearing's value of a parameter as one
    for group in ([cases] if pooled else [[c] for c in cases]):
        z, runs, trusted, held = {}, 0, 0, []
        for case, seed, d in ((c, s, d) for c in group for s, d in runs_of(jd, c)):
            runs += 1
            trusted += d["trusted"]
            if only_trusted and not d["trusted"]:
                continue
            with open(os.path.join(rd, f"{case}-{seed}", "truth.json")) as fh:
                truth = json.load(fh)
            for (b, k), v in z_values(d, truth).items():
                if pooled:
                    z.setdefault(("all", k), []).append((f"{case}-{seed} {b}", v))
                else:
                    z.setdefault((b, k), []).append((seed, v))
            held += [f"{case}-{seed} {b} {k} = {v:g} (truth {tp:g})" for b, k, v in held_values(d, truth)
                     for tp in [next(p[k] for p in truth["pedestals"] if p["bearing"] == b)]]
        case = " + ".join(group)
        print(f"{case}: {runs} runs, {trusted} trusted{' (trusted only below)' if only_trusted else ''}")
        print("| bearing | parameter | n | mean z (95 %) | RMS z (95 %) | beyond 3 ± |")
        print("|---|---|---|---|---|---|")
        for (b, k), v in sorted(z.items()):
            n = len(v)
            zs = [x for _, x in v]
            mean = sum(zs) / n
            sd = math.sqrt(sum((x - mean) ** 2 for x in zs) / max(n - 1, 1))
            half = 1.96 * sd / math.sqrt(n)
            rms = math.sqrt(sum(x * x for x in zs) / n)
            lo, hi = (rms * math.sqrt(n / chi2.ppf(q, n)) for q in (0.975, 0.025))
            big = [f"{s} ({x:+.2f})" for s, x in v if abs(x) > 3]
            print(f"| {b} | {k} | {n} | {mean:+.2f} ({mean - half:+.2f}..{mean + half:+.2f}) "
                  f"| {rms:.2f} ({lo:.2f}..{hi:.2f}) | {len(big)}{' ' + ', '.join(big) if big else ''} |")
        if held:
            print(f"\nheld without a ± where the truth is not zero: {len(held)}: {'; '.join(held)}")
        km = [x for (b, k), v in z.items() if k in ("k_y", "k_z", "m") for _, x in v]
        if km:
            n = len(km)
            p2, p3 = (math.erfc(c / math.sqrt(2)) for c in (2, 3))
            print(f"\npooled k_y, k_z, m: {n} values, beyond 2 ±: {sum(abs(x) > 2 for x in km)} "
                  f"(normal {n * p2:.1f}), beyond 3 ±: {sum(abs(x) > 3 for x in km)} (normal {n * p3:.2f}), "
                  f"RMS {math.sqrt(sum(x * x for x in km) / n):.2f}")
        print()


if __name__ == "__main__":
    main()
