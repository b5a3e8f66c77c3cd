#!/usr/bin/env python3
"""A time-domain recording of a run-down of one of scripts/ross_unseen.py's
machines, made from ROSS 2.3.0's steady unbalance response, for `plinth
extract` (docs/field-data.md, formats.md "Recorded waveforms").

Usage:
  ross_recording.py [--machine NAME] OUT CASE SEED [KEY=VALUE...]
        OUT/recording.wav, channels.toml, bearings.csv, truth.json and
        steady.npz (the dense ROSS response the signals were made from)
  ross_recording.py --check RUN OUT [EXPECTED.csv]
        each channel's extracted phasors (RUN/measurements.csv) against
        OUT/steady.npz at the row's speed: rms |error|, rms sd (the noise
        columns), mean |error|^2/sd^2 (1 when the columns are calibrated);
        with EXPECTED.csv, ROSS's phasors at the rows' speeds written there
        (speed_hz, bearing, then measurements.csv's phasor columns)
  ross_recording.py --null RUN OUT NEW SEED
        RUN copied to NEW with every phasor replaced by OUT/steady.npz's at
        the row's speed plus complex white noise of exactly the row's noise
        column (sd/sqrt 2 per part): data that follow the columns' own
        model, to test a reader of the columns apart from the extraction
KEY=VALUE (defaults): top, bottom [Hz] (the machine's grid), rate=1.0
[Hz/s, the run-down's deceleration], fs=12800 [samples/s], bits=16,
probe_mv=5.0 and pickup_mv=1.0 [mV rms of white noise per sample],
revolutions=4 [per phasor], two_x=0.1 [the 2X, of each channel's rms 1X],
kp_ramp_deg=2.0 [the keyphasor notch's edges, shaft degrees],
profile=F0,F1@RATE,~SECONDS,... [the speed: from F0 Hz, then each step
either to F1 Hz at RATE Hz/s (up or down) or a dwell of SECONDS at the
speed reached; replaces top, bottom and rate, e.g. profile=50,30@2,~5,
40@1,10@2: a run-down with a dwell at 30 Hz and a run-up to 40 Hz].
CASE: "clean" or one of the machine's effects in ross_unseen_machines.py
whose effects ROSS simulates or that act on the phasors at every speed
(sub-base, frame, table, cross, runout, delay; not flips or outliers).

ROSS's response (ross_unseen.respond: its rotor, bearings, pedestals,
effects) on a dense speed grid (0.1 Hz) is interpolated with a cubic
spline in speed; at each sample the channel reads the steady 1X response
at the instantaneous speed f(t) = top - rate t, shaft angle
theta(t) = 2 pi (top t - rate t^2/2) + theta0 (q(t) = Re{Q e^{i theta}},
formats.md). Per bearing: two proximity probes at +-45 deg (rel, 7.87
mV/um on a -9 V gap), two velocity pick-ups at 0 and 90 deg (ped, 100
mV/(in/s), reading Re{(i Omega Q + dQ/dt) e^{i theta}}, dQ/dt = Q'(f)
df/dt); each channel a 2X of fixed phase and white noise; a notch
keyphasor (-1 V, -9 V in the notch) as the last channel; integer PCM at
full scale 10 V. Seeded: the seed fixes the noise and theta0.
With a profile, f(t) is piecewise linear (theta its integral, exact at
each sample) and dQ/dt = Q'(f) df/dt with df/dt of the sample's segment.
"""
import csv
import json
import math
import os
import sys
import wave

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ross_unseen as ru  # noqa: E402

PROBE_V_PER_M = 7.87e3          # 7.87 mV/um
PICKUP_V_PER_M_S = 100.0 / 25.4  # 100 mV/(in/s) [V/(m/s)]
GAP_V = -9.0
FULL_SCALE_V = 10.0
STEP_HZ = 0.1                   # the dense ROSS grid
TRANSDUCERS = (("rel", 45.0), ("rel", -45.0), ("ped", 0.0), ("ped", 90.0))


def dense(machine, case, top, bottom, cache):
    """(speeds, {bearing: {channel: complex array}}, written tables) of ROSS
    on the dense grid, cached in `cache` (npz) per machine and case."""
    from scipy.interpolate import CubicSpline  # noqa: F401  (fail early without scipy)
    effects = [] if case == "clean" else ru.MACHINES[machine]["effects"][case]
    physical = [e for e in effects if e[0] in ("frame", "sub_base", "worn_film", "table_scale", "cross")]
    speeds = np.round(np.arange(bottom - 1.0, top + 1.0 + STEP_HZ / 2, STEP_HZ), 4)
    if os.path.exists(cache):
        z = np.load(cache, allow_pickle=True)
        return z["speeds"], z["resp"].item(), z["written"].item(), effects
    import tomllib
    with open(ru.machine_file(machine), "rb") as f:
        spec = tomllib.load(f)
    resp, written = ru.respond(spec, speeds, physical)
    np.savez(cache, speeds=speeds, resp=np.array(resp, dtype=object), written=np.array(written, dtype=object))
    return speeds, resp, written, effects


def truth_of(machine, resp, speeds, effects):
    """truth.json as ross_unseen.make writes it; applies runout and delay to
    `resp` (in place)."""
    details, bases = [], []
    for e in effects:
        if e[0] == "runout":
            details.append({"name": "probe_runout", "bearing": e[1], "parameters": ru.add_runout(resp, e[1])})
        elif e[0] == "delay":
            details.append({"name": "sensor_delay", "bearing": e[1],
                            "parameters": ru.add_delay(resp, e[1], speeds, e[2])})
        elif e[0] in ("frame", "sub_base", "worn_film", "table_scale", "cross"):
            import tomllib
            with open(ru.machine_file(machine), "rb") as f:
                details.append(ru.physical_detail(e, tomllib.load(f)))
        else:
            sys.exit(f"effect {e[0]}: not made in a recording")
        if e[0] == "frame":
            bases.append(dict(e[1], eta=0.0))
        if e[0] == "sub_base":
            bases.append({"name": f"{e[1]['bearing']}-sub-base", "bearings": [e[1]["bearing"]], "eta": 0.0,
                          **{k: v for k, v in e[1].items() if k != "bearing"}})
    truth = {"pedestals": ru.nominal_truth(machine), "effects": [d["name"] for d in details],
             "effect_details": details}
    if bases:
        truth["bases"] = bases
    return truth


def make(machine, out, case, seed, opt):
    from scipy.interpolate import CubicSpline
    grid = ru.MACHINES[machine]["grid"](False, 1)
    top, bottom = opt.get("top", float(grid.max())), opt.get("bottom", float(grid.min()))
    rate, fs = opt.get("rate", 1.0), opt.get("fs", 12800.0)
    os.makedirs(out, exist_ok=True)
    cache = os.path.join(os.path.dirname(os.path.abspath(out)), f"ross-{machine}-{case}.npz")
    speeds, resp, written, effects = dense(machine, case, top, bottom, cache)
    resp = {b: dict(v) for b, v in resp.items()}
    truth = truth_of(machine, resp, speeds, effects)
    names = list(resp)
    rng = np.random.default_rng(1_000 * seed + 17)
    if "profile" in opt:
        t, f, dfdt, turns = profile(opt["profile"], fs)
        if f.min() < speeds[0] or f.max() > speeds[-1]:
            sys.exit(f"profile: speeds {f.min():.3g}..{f.max():.3g} Hz beyond the machine's {speeds[0]}..{speeds[-1]} Hz")
        theta = 2 * math.pi * turns + 2 * math.pi * rng.random()
    else:
        duration = (top - bottom) / rate
        t = np.arange(int(duration * fs)) / fs
        f = top - rate * t
        dfdt = np.full_like(t, -rate)
        theta = 2 * math.pi * (top * t - 0.5 * rate * t * t) + 2 * math.pi * rng.random()
    rot = np.exp(1j * theta)
    channels, signals = [], []
    for b in names:
        for q, a in TRANSDUCERS:
            v = math.cos(math.radians(a)) * resp[b][f"{q}_y"] + math.sin(math.radians(a)) * resp[b][f"{q}_z"]
            s = CubicSpline(speeds, v)
            x = s(f)
            if q == "rel":
                one = PROBE_V_PER_M * x
                dc, noise = GAP_V, opt.get("probe_mv", 5.0) * 1e-3
            else:  # velocity: d/dt Re{X e^{i theta}} = Re{(i Omega X + X'(f) df/dt) e^{i theta}}
                one = PICKUP_V_PER_M_S * (2j * math.pi * f * x + s(f, 1) * dfdt)
                dc, noise = 0.0, opt.get("pickup_mv", 1.0) * 1e-3
            rms = math.sqrt(float(np.mean(np.abs(one) ** 2)))
            two = opt.get("two_x", 0.1) * rms * np.exp(1j * (2 * theta + rng.uniform(0, 2 * math.pi)))
            signals.append(dc + (one * rot).real + two.real + noise * rng.standard_normal(len(t)))
            channels.append((b, q, a))
    # notch keyphasor: -1 V, -9 V for 12 deg (edges kp_ramp_deg wide); the falling edge's middle at theta = 2 pi k
    ramp, width = math.radians(opt.get("kp_ramp_deg", 2.0)), math.radians(12.0)
    phi = np.mod(theta + 0.5 * ramp, 2 * math.pi)
    kp = np.interp(phi, [0, ramp, width, width + ramp, 2 * math.pi], [-1.0, -9.0, -9.0, -1.0, -1.0])
    signals.append(kp + 1e-3 * rng.standard_normal(len(t)))
    bits = int(opt.get("bits", 16))
    full = (1 << (bits - 1)) - 1
    codes = np.clip(np.round(np.array(signals).T / FULL_SCALE_V * full), -full - 1, full)
    with wave.open(os.path.join(out, "recording.wav"), "wb") as w:
        w.setnchannels(len(signals))
        w.setsampwidth(bits // 8)
        w.setframerate(int(fs))
        w.writeframes(codes.astype({16: "<i2", 32: "<i4"}[bits]).tobytes())
    lines = [f"full_scale_v = {FULL_SCALE_V}", f"revolutions = {int(opt.get('revolutions', 4))}", "",
             "[keyphasor]", f"channel = {len(channels)}", "threshold_v = -5.0", 'edge = "falling"', ""]
    for i, (b, q, a) in enumerate(channels):
        lines += ["[[channel]]", f"index = {i}", f'bearing = "{b}"', f'quantity = "{q}"', f"angle_deg = {a}"]
        lines += (['sensor = "proximity"', "sensitivity = 7.87", 'sensitivity_unit = "V/mm"'] if q == "rel" else
                  ['sensor = "velocity"', "sensitivity = 100.0", 'sensitivity_unit = "mV/(in/s)"'])
        lines.append("")
    with open(os.path.join(out, "channels.toml"), "w") as fh:
        fh.write("\n".join(lines))
    with open(os.path.join(out, "bearings.csv"), "w") as fh:
        fh.write("speed_hz,bearing," + ",".join(ru.KEYS) + "\n")
        for j in range(0, len(speeds), 2):
            for b in names:
                fh.write(",".join([f"{speeds[j]:.6g}", b] + [ru.sig(written[b][j][k], 10) for k in ru.KEYS]) + "\n")
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1)
        fh.write("\n")
    np.savez(os.path.join(out, "steady.npz"), speeds=speeds,
             **{f"{b}.{c}": resp[b][c] for b in names for c in ru.CHANNELS})


def profile(spec, fs):
    """(t, f, df/dt, revolutions) at each sample of the profile `spec`
    (docstring: F0,F1@RATE,~SECONDS,...): f piecewise linear in t, the
    revolutions its exact integral."""
    steps = spec.split(",")
    f0 = float(steps[0])
    knots = [(0.0, f0)]
    for step in steps[1:]:
        t0, fa = knots[-1]
        if step.startswith("~"):
            knots.append((t0 + float(step[1:]), fa))
        else:
            fb, _, r = step.partition("@")
            fb, r = float(fb), float(r)
            knots.append((t0 + abs(fb - fa) / r, fb))
    kt, kf = np.array([k[0] for k in knots]), np.array([k[1] for k in knots])
    t = np.arange(int(kt[-1] * fs)) / fs
    f = np.interp(t, kt, kf)
    seg = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, len(kt) - 2)
    slope = (kf[seg + 1] - kf[seg]) / (kt[seg + 1] - kt[seg])
    # revolutions at each knot, then within the segment: f_k dt + slope dt^2/2
    at = np.concatenate([[0.0], np.cumsum(0.5 * (kf[1:] + kf[:-1]) * np.diff(kt))])
    dt = t - kt[seg]
    return t, f, slope, at[seg] + kf[seg] * dt + 0.5 * slope * dt * dt


def check(run, out, expected=None):
    """Prints and returns {(bearing, channel): (rms |err|, rms sd, mean z^2, rows)}."""
    from scipy.interpolate import CubicSpline
    z = np.load(os.path.join(out, "steady.npz"))
    rows = list(csv.DictReader(open(os.path.join(run, "measurements.csv"))))
    res, table = {}, {}
    for b in sorted({r["bearing"] for r in rows}):
        rb = [r for r in rows if r["bearing"] == b]
        sp = np.array([float(r["speed_hz"]) for r in rb])
        for c in ru.CHANNELS:
            got = np.array([complex(float(r[c + "_re"]), float(r[c + "_im"])) for r in rb])
            want = CubicSpline(z["speeds"], z[f"{b}.{c}"])(sp)
            for r, w in zip(rb, want):
                table.setdefault((r["speed_hz"], b), {})[c] = w
            err = np.abs(got - want)
            sd = np.array([float(r.get(c + "_sd") or "nan") for r in rb])
            res[(b, c)] = (math.sqrt(np.mean(err**2)), math.sqrt(np.mean(sd**2)), float(np.mean(err**2 / sd**2)),
                           len(rb))
            print(f"{b} {c}: rms err {res[(b, c)][0]:.3e} m, rms sd {res[(b, c)][1]:.3e} m, "
                  f"mean err^2/sd^2 {res[(b, c)][2]:.2f}, peak {np.abs(want).max():.3e} m ({len(rb)} rows)")
    if expected:
        with open(expected, "w") as f:
            f.write("speed_hz,bearing," + ",".join(f"{c}_re,{c}_im" for c in ru.CHANNELS) + "\n")
            for (s, b), v in table.items():
                f.write(f"{s},{b}," + ",".join(f"{v[c].real:.9e},{v[c].imag:.9e}" for c in ru.CHANNELS) + "\n")
    return res


def null(run, out, new, seed):
    """--null: RUN's rows with ROSS's phasors plus noise drawn from the columns."""
    import shutil
    from scipy.interpolate import CubicSpline
    shutil.rmtree(new, ignore_errors=True)
    shutil.copytree(run, new)
    z = np.load(os.path.join(out, "steady.npz"))
    rng = np.random.default_rng(int(seed))
    rows = list(csv.DictReader(open(os.path.join(run, "measurements.csv"))))
    for r in rows:
        for c in ru.CHANNELS:
            q = CubicSpline(z["speeds"], z[f"{r['bearing']}.{c}"])(float(r["speed_hz"]))
            n = float(r[c + "_sd"]) / math.sqrt(2) * complex(rng.standard_normal(), rng.standard_normal())
            r[c + "_re"], r[c + "_im"] = f"{(q + n).real:.9e}", f"{(q + n).imag:.9e}"
    with open(os.path.join(new, "measurements.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main():
    args = sys.argv[1:]
    if args[:1] == ["--null"] and len(args) == 5:
        null(*args[1:])
        return
    if args[:1] == ["--check"] and len(args) in (3, 4):
        check(*args[1:])
        return
    machine = ru.DEFAULT
    if args[:1] == ["--machine"] and len(args) >= 2 and args[1] in ru.MACHINES:
        machine, args = args[1], args[2:]
    if len(args) < 3 or not (args[1] == "clean" or args[1] in ru.MACHINES[machine]["effects"]):
        sys.exit(__doc__)
    opt = {k: (v if k == "profile" else float(v)) for k, v in (a.split("=", 1) for a in args[3:])}
    make(machine, args[0], args[1], int(args[2]), opt)


if __name__ == "__main__":
    main()
