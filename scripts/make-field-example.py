#!/usr/bin/env python3
"""Writes examples/field/: the field-data inputs of the README's quick start,
made from a run simulated by `plinth simulate` (scripts/make-field-example.sh
runs both), independently of Plinth's readers (Python stdlib only).

Usage: make-field-example.py SIM_DIR OUT_DIR

SIM_DIR is a run directory of examples/feng-hahn-1997-damped.toml on a fine
speed grid (measurements.csv, bearings.csv, truth.json). OUT_DIR receives:

- vector-table.csv + layout.toml: a 1X vector table as an ADRE/System 1
  export prints it: speed in rpm, per bearing two proximity probes at 45L and
  45R (um pp, 3 significant digits, phase lag in whole degrees, seen from the
  driver with the shaft turning CCW) and two velocity pick-ups at 0 and 90
  degrees (mm/s pk, 3 significant digits, lag in whole degrees), columns in
  an instrument's order with an extra column.
- recording.wav + channels.toml: a 24-bit PCM recording of a run-down from
  70 Hz to 20 Hz at 10 Hz/s, 5120 samples/s, nine channels: the four probes
  (7.87 V/mm on a -9 V gap), four pedestal displacement transmitters
  (7.87 V/mm, at 0 and 90 degrees) and a
  notch keyphasor, with 0.5 mV of white noise on every channel.
- bearings.csv: the known bearing coefficients (SIM_DIR's, every 0.25 Hz).
- truth.json: the pedestals the data were made from (copied from SIM_DIR;
  the unbalance scale does not change them).

Conventions (docs/formats.md): a transducer at angle a (degrees from +y
towards +z) reads cos(a)*Y + sin(a)*Z; q(t) = Re{Q exp(i theta(t))} with
theta the shaft angle since a keyphasor pulse; phase lag = -arg(Q).
"""
import cmath
import csv
import math
import os
import random
import shutil
import struct
import sys
import wave

TAU = 2.0 * math.pi
# The response is linear in the unbalance: the example machine's unbalance
# times SCALE gives amplitudes a field instrument shows (probes up to about
# 13 um pp, pedestals up to about 40 mm/s pk at their resonances).
SCALE = 5.0


def read_run(path):
    """{bearing: [(speed_hz, {"rel": (Y, Z), "ped": (Y, Z)})]} sorted by speed."""
    out = {}
    with open(os.path.join(path, "measurements.csv")) as f:
        for r in csv.DictReader(f):
            c = lambda k: SCALE * complex(float(r[k + "_re"]), float(r[k + "_im"]))
            out.setdefault(r["bearing"], []).append(
                (float(r["speed_hz"]), {"rel": (c("rel_y"), c("rel_z")), "ped": (c("ped_y"), c("ped_z"))}))
    for rows in out.values():
        rows.sort(key=lambda x: x[0])
    return out


def at(rows, f, quantity, axis):
    """Linear interpolation of one phasor component in speed, and its
    derivative in speed [per Hz]."""
    lo, hi = 0, len(rows) - 1
    if not rows[lo][0] <= f <= rows[hi][0]:
        raise ValueError(f"speed {f} Hz outside the simulated grid")
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if rows[mid][0] <= f:
            lo = mid
        else:
            hi = mid
    (f0, a), (f1, b) = rows[lo], rows[hi]
    qa, qb = a[quantity][axis], b[quantity][axis]
    w = (f - f0) / (f1 - f0)
    return qa + w * (qb - qa), (qb - qa) / (f1 - f0)


def reading(yz, angle_deg):
    a = math.radians(angle_deg)
    return math.cos(a) * yz[0] + math.sin(a) * yz[1]


def sig(x, digits):
    """x rounded to `digits` significant digits, as text without exponent."""
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    decimals = max(digits - 1 - mag, 0)
    return f"{round(x, digits - 1 - mag):.{decimals}f}"


# (label, angle_deg, Bently angle) of the transducers at every bearing.
PROBES = [("45L", 45.0), ("45R", -45.0)]      # rel: proximity probes, view driver, CCW
PICKUPS = [("0", 0.0), ("90", 90.0)]          # ped: velocity pick-ups


def write_table(run, out):
    bearings = list(run)
    speeds = [f for f, _ in run[bearings[0]] if abs(f - round(f)) < 1e-9 and 15.0 <= f <= 75.0]
    header = ["Sample", "Speed (rpm)"]
    for b in bearings:
        for name, _ in PROBES:
            header += [f"{b} {name} 1X Amp", f"{b} {name} 1X Phase"]
        for name, _ in PICKUPS:
            header += [f"{b} vel {name} 1X Amp", f"{b} vel {name} 1X Phase"]
    rows = []
    for i, f in enumerate(sorted(speeds, reverse=True)):   # a run-down, as recorded
        row = [str(i + 1), f"{f * 60.0:.0f}"]
        for b in bearings:
            data = dict(run[b])[f]
            for _, angle in PROBES:
                q = reading(data["rel"], angle)          # m, 0-pk
                row += [sig(2.0 * abs(q) * 1e6, 3), f"{(-math.degrees(cmath.phase(q))) % 360.0:.0f}"]
            for _, angle in PICKUPS:
                v = 1j * TAU * f * reading(data["ped"], angle)   # m/s, 0-pk
                row += [sig(abs(v) * 1e3, 3), f"{(-math.degrees(cmath.phase(v))) % 360.0:.0f}"]
        rows.append(row)
    with open(os.path.join(out, "vector-table.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    lines = [
        "# The columns of vector-table.csv (docs/formats.md, \"A 1X vector table\").",
        "# Made by scripts/make-field-example.sh.",
        'phase = "lag"                                  # Bently: degrees from the keyphasor to the positive peak',
        'speed = { column = "Speed (rpm)", unit = "rpm" }',
        'view = "driver"                                # probe angles as seen from the driver end',
        'rotation = "ccw"                               # the shaft turns counter-clockwise seen from there',
        "",
    ]
    for b in bearings:
        for name, _ in PROBES:
            lines += [
                "[[transducer]]",
                f'bearing = "{b}"',
                'quantity = "rel"                               # proximity probe: shaft relative to the pedestal',
                f'angle = "{name}"',
                f'amplitude = {{ column = "{b} {name} 1X Amp", unit = "um pp" }}',
                f'phase = {{ column = "{b} {name} 1X Phase" }}',
                "",
            ]
        for name, angle in PICKUPS:
            lines += [
                "[[transducer]]",
                f'bearing = "{b}"',
                'quantity = "ped"                               # velocity pick-up on the pedestal',
                f"angle_deg = {angle}",
                f'amplitude = {{ column = "{b} vel {name} 1X Amp", unit = "mm/s pk" }}',
                f'phase = {{ column = "{b} vel {name} 1X Phase" }}',
                "",
            ]
    with open(os.path.join(out, "layout.toml"), "w") as fh:
        fh.write("\n".join(lines))


RATE = 5120          # samples per second per channel (73 per revolution at 70 Hz)
F_START, F_END, DECEL = 70.0, 20.0, 10.0   # Hz, Hz, Hz/s
FULL_SCALE_V = 10.0
PROBE_V_PER_M = 7.87e3        # 7.87 V/mm
GAP_V = -9.0
PICKUP_V_PER_M_S = 100.0      # 100 mV/(mm/s)
# The pedestal pick-ups of the recording: displacement transmitters (a
# seismic sensor with integrated displacement output, 7.87 V/mm here). A
# velocity pick-up's conversion D = V/(iΩ) assumes a steady response, which a
# 10 Hz/s sweep through these lightly damped (ζ ≈ 0.2 %) pedestal resonances
# is not (dQ/dt is a third of ΩQ there): the table carries the velocity
# pick-ups instead.
PED_SENSOR = "proximity"
NOISE_V = 0.0005
KP_HIGH, KP_LOW, KP_WIDTH = -1.0, -9.0, math.radians(12.0)   # notch under the keyphasor probe
KP_RAMP = math.radians(2.0)


def write_recording(run, out):
    bearings = list(run)
    rng = random.Random(1997)
    duration = (F_START - F_END) / DECEL
    frames = int(duration * RATE)
    channels = []   # (bearing, quantity, angle, kind)
    for b in bearings:
        channels += [(b, "rel", a, "proximity") for _, a in PROBES]
        channels += [(b, "ped", a, PED_SENSOR) for _, a in PICKUPS]
    # Keyphasor pulse k at theta = 2*pi*k; theta(0) set so that the first
    # pulse comes a quarter revolution after the start.
    theta0 = -0.25 * TAU
    data = bytearray()
    for n in range(frames):
        t = n / RATE
        f = F_START - DECEL * t
        theta = theta0 + TAU * (F_START * t - 0.5 * DECEL * t * t)
        omega = TAU * f
        sample = []
        for b, quantity, angle, kind in channels:
            y, dy = at(run[b], f, quantity, 0)
            z, dz = at(run[b], f, quantity, 1)
            q = reading((y, z), angle)
            dq = reading((dy, dz), angle) * (-DECEL)          # dQ/dt along the run-down
            if kind == "proximity" and quantity == "rel":
                v = GAP_V + PROBE_V_PER_M * (q * cmath.exp(1j * theta)).real
            elif kind == "proximity":
                v = PROBE_V_PER_M * (q * cmath.exp(1j * theta)).real
            else:
                v = PICKUP_V_PER_M_S * ((1j * omega * q + dq) * cmath.exp(1j * theta)).real
            sample.append(v + rng.gauss(0.0, NOISE_V))
        # Notch: the falling edge's midpoint at theta = 2*pi*k.
        phi = (theta + 0.5 * KP_RAMP) % TAU
        if phi < KP_RAMP:
            kp = KP_HIGH + (KP_LOW - KP_HIGH) * phi / KP_RAMP
        elif phi < KP_WIDTH:
            kp = KP_LOW
        elif phi < KP_WIDTH + KP_RAMP:
            kp = KP_LOW + (KP_HIGH - KP_LOW) * (phi - KP_WIDTH) / KP_RAMP
        else:
            kp = KP_HIGH
        sample.append(kp + rng.gauss(0.0, NOISE_V))
        for v in sample:
            code = max(-(1 << 23), min((1 << 23) - 1, round(v / FULL_SCALE_V * ((1 << 23) - 1))))
            data += struct.pack("<i", code)[:3]
    with wave.open(os.path.join(out, "recording.wav"), "wb") as w:
        w.setnchannels(len(channels) + 1)
        w.setsampwidth(3)
        w.setframerate(RATE)
        w.writeframes(bytes(data))
    lines = [
        "# The channels of recording.wav (docs/formats.md, \"Recorded waveforms\").",
        "# Made by scripts/make-field-example.sh.",
        f"full_scale_v = {FULL_SCALE_V}                # 24-bit PCM: volts at full scale",
        "revolutions = 4                    # revolutions per phasor",
        'view = "driver"',
        'rotation = "ccw"',
        "",
        "[keyphasor]",
        f"channel = {len(channels)}",
        "threshold_v = -5.0",
        'edge = "falling"                   # a notch under the keyphasor probe',
        "",
    ]
    for i, (b, quantity, angle, kind) in enumerate(channels):
        lines += ["[[channel]]", f"index = {i}", f'bearing = "{b}"', f'quantity = "{quantity}"']
        if kind == "proximity" and quantity == "ped":
            lines += [f"angle_deg = {angle}", 'sensor = "proximity"             # displacement transmitter on the pedestal',
                      "sensitivity = 7.87", 'sensitivity_unit = "V/mm"']
        elif kind == "proximity":
            name = [p for p, a in PROBES if a == angle][0]
            lines += [f'angle = "{name}"', 'sensor = "proximity"', "sensitivity = 7.87",
                      'sensitivity_unit = "V/mm"']
        else:
            lines += [f"angle_deg = {angle}", 'sensor = "velocity"', "sensitivity = 100.0",
                      'sensitivity_unit = "mV/(mm/s)"']
        lines.append("")
    with open(os.path.join(out, "channels.toml"), "w") as fh:
        fh.write("\n".join(lines))


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sim, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    run = read_run(sim)
    write_table(run, out)
    write_recording(run, out)
    # The bearing table every 0.25 Hz (coefficients are interpolated
    # linearly in speed between listed rows; they vary slowly).
    with open(os.path.join(sim, "bearings.csv")) as src, open(os.path.join(out, "bearings.csv"), "w") as dst:
        for i, line in enumerate(src):
            speed = line.split(",", 1)[0]
            if i == 0 or abs(float(speed) * 4.0 - round(float(speed) * 4.0)) < 1e-9:
                dst.write(line)
    shutil.copy(os.path.join(sim, "truth.json"), os.path.join(out, "truth.json"))


if __name__ == "__main__":
    main()
