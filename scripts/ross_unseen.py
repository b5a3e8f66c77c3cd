#!/usr/bin/env python3
"""Run directories of machines Plinth was never tuned to, made by ROSS 2.3.0.

Usage:
  python3 scripts/ross_unseen.py [--machine NAME] OUT CASE[,CASE...] SEED...
                                       run directories OUT/CASE-SEED
  python3 scripts/ross_unseen.py [--machine NAME] --cases   the case names
  python3 scripts/ross_unseen.py [--machine NAME] --repo    the stored runs
        (the machine's data directory/<case>/, seed 1 of its repo cases)
  python3 scripts/ross_unseen.py --tilting-pad
        unseen-flex's bearing table (TOML rows) from ROSS's TiltingPad
  python3 scripts/ross_unseen.py --compare RUN_A RUN_B
        worst |A - B| per bearing and channel, in % of B's peak (the check
        of a ROSS run against `plinth simulate` of the machine file)
NAME: unseen-four (default), unseen-overhung, unseen-train, unseen-flex,
unseen-five, unseen-six, unseen-seven, unseen-eight, unseen-nine or
unseen-ten (described in ross_unseen_machines.py).

Needs ROSS 2.3.0 (`pip install ross-rotordynamics==2.3.0 "plotly<6"`).
Deterministic: the seed fixes the noise, the flipped and outlier speeds and
(digit cases) the speed grid.

unseen-four is tests/data/ross-unseen/unseen-four.toml (read with
tomllib): four bearings, an overhung disk, two tabulated and two oil-film
bearings, pedestals of 70-240 kg, B4 undamped; speeds 6-126 Hz in 1.25 Hz
steps; 1 % white noise of each channel's RMS.

unseen-overhung is tests/data/ross-unseen-2/unseen-overhung.toml: an
overhung single-stage compressor, two bearings 0.32 m apart, a 110 kg
impeller overhung 0.28 m, B1 a tilting-pad-like table (no cross-coupling,
k and c rising with speed), B2 a short-bearing oil film, pedestals with
k_z = 0.3 k_y. Its speeds are a windage-braked coast-down sampled every
few revolutions (dOmega/dt = -b Omega^2: a constant ratio between
successive speeds, so the grid is geometric, dense at low speed), 150 Hz
down to 8 Hz; its noise is heteroscedastic, as a real probe's: sigma = 1 %
of each phasor's amplitude plus a floor of 0.1 % of the channel's RMS.

unseen-train is tests/data/ross-unseen-3/unseen-train.toml: a motor-pump
train as one flexible shaft on three bearings (B1 a cross-coupled sleeve
table on a pedestal ten times stiffer than its bearing, B2 an oil film, B3
a stiff lightly damped table on a soft bracket, the impeller overhung
beyond it; B3's rel is tiny over most of the range and B2's rel_y passes
near a node at 50 Hz). Its speeds are a run-up at constant acceleration
sampled every few revolutions (Omega^2 in equal steps: dense at high
speed), 5 to 85 Hz, with the band 38-46 Hz skipped (136 speeds left); its
noise differs by kind of sensor: pedestal pick-ups sigma = 2 % of |phasor|
(no floor), proximity probes a constant sigma of 0.5 % of the channel's
RMS. Its digit case clean-dmix writes B1 at 2 significant digits, B2 at 3
and B3 at 4.

unseen-flex is tests/data/ross-unseen-4/unseen-flex.toml: a long flexible
roll (3.45 m, three shell masses and an overhung hub) on two tilting-pad
bearings whose table is ROSS's own THD TiltingPad element (symmetric
cross terms, large damping, stiffness rising with speed), run through its
bending modes (16, 37, 54, 75, 82 Hz peaks); B1's pedestal a block 30-50
times stiffer than its bearing (its pick-ups near their floor), B2's a soft
bracket with k_y = 3 k_z. Its speeds are a run-down sampled unevenly (steps
0.3-1.7 of the mean, fixed), 110 Hz down to 12 Hz, with 55-61 Hz lost (a
recorder drop-out); its noise is each sensor's own: probes 0.5 % of
|phasor| + 0.05 um, pick-ups 1 % + a velocity floor of 1 um/s (largest at
low speed).

unseen-five is tests/data/ross-unseen-5/unseen-five.toml: a fan rotor on
two plain bearings with strong cross-coupling (B1 a lightly loaded short
sleeve bearing, B2 a skew cross-coupled table), a 170 kg wheel overhung
0.36 m beyond B2, pedestals four times stiffer vertically than
horizontally, their horizontal resonances (29, 36 Hz) inside the run.
Its speeds are a coarse run-down table, one speed every 1.5 Hz from 56.1 Hz
down to 9.6 Hz (32 speeds, below the oil whip onset at 59 Hz); its noise is the largest of the five: 3 % of |phasor|
plus a floor of 0.3 % of the channel's RMS.

unseen-seven is tests/data/ross-unseen-7/unseen-seven.toml: a steam
turbine-generator set on three heavily loaded plain journals (short oil
films, strongly cross-coupled), a single-bearing generator rigidly coupled
to the turbine, heavy pedestals whose horizontal resonances and the rotor's
criticals lie inside a trip coast-down logged every 0.75 Hz (50 to 5 Hz);
probes 0.4 % of |phasor| + 0.05 um, velocity pick-ups 1 % + 5 um/s. Its
three departures: "thermal" (the films' viscosity rising as the speed falls,
bearings.csv at the design viscosity), "ped_delay" (one bearing's pedestal
pick-ups read late: sensor_delay on the ped channels) and "sweep" (each
phasor the mean over the speeds a tracking filter's block of revolutions
spans in a fast coast-down).

unseen-eight is tests/data/ross-unseen-8/unseen-eight.toml: a high-speed
centrifugal gas compressor on two tilting-pad journals (tables, no
cross-coupling), light stiff pedestals on a common skid, the rotor's first
criticals (about 184 and 242 Hz) inside a fast trip run-down logged every
0.4 Hz from 250 to 100 Hz (376 speeds); probes 0.5 % of |phasor| +
0.02 um, casing accelerometers 1 % + 5 mm/s^2. Its three departures:
"probe_axes" (both bearings' probes at +-45 deg from the vertical, written
as they read, not resolved to y and z), "speed_lag" (the speed column
0.25 Hz high: the speed filter's lag in the 5 Hz/s run-down) and
"corr_noise" (the tracking filter's time constant longer than the time
between vectors: each channel's noise an AR(1) along the run, rho 0.80).

unseen-nine is tests/data/ross-unseen-9/unseen-nine.toml: a large
turbocharger, both wheels overhung outboard of two floating-ring journals
(a strongly speed-dependent, cross-coupled table), B1's housing end light
and stiff, B2's (hot turbine end) softer with its resonances inside an
exponential coast-down from 500 Hz to 100 Hz (90 speeds, a vector a
second); probes 0.5 % of |phasor| + 0.01 um, accelerometers 1 % +
2 mm/s^2. Its three departures, each following the turbine end's cooling
after the engine stops (cooling_fraction): "ped_drift" (B2's pedestal
stiffness rising 4 % over the run), "runout_drift" (B2's probe runout
growing 1.8-fold and turning 40 deg over the run), and "probe_gain" (B1's
vertical probe reading 5 % low: calibrated on another steel); and
"ped-drift-up", ped-drift's machine run up instead (the drift following
time, so reversed in speed: the second run a compare needs).

unseen-ten is tests/data/ross-unseen-10/unseen-ten.toml: a two-pole
induction motor on a variable-frequency drive, the first symmetric machine:
isotropic ball-bearing tables (no cross-coupling, almost no damping),
nearly isotropic end-shield pedestals (k_z 6-7 % below k_y) whose
resonances (76-87 Hz) and the rotor's first critical lie inside the drive's
ramp-down from 100 Hz to 10 Hz, a vector every 2 Hz (46 speeds): near
circular orbits. Probes 0.5 % of |phasor| + 0.03 um, velocity pick-ups 1 %
+ 2 um/s.

Each machine is built in ROSS here, not by Plinth: Timoshenko shaft elements
(shear, rotary inertia, gyroscopics), DiskElements, each bearing a
BearingElement from the shaft node to a PointMass (n_link, the pedestal),
the pedestal a BearingElement to the ground, to a shared base PointMass, or
to its own sub-base PointMass. Oil-film coefficients come from the
short-bearing closed form of tests/reference/ross/make_reference.py
(`ocvirk`, Python, not Plinth's code) at exactly the run's speeds; tables
are interpolated linearly in speed. The response is ROSS's
run_unbalance_response; the run directory is written here following
docs/formats.md directly (rel = rotor - pedestal, ped absolute, y vertical,
z horizontal, q(t) = Re{Q e^{iWt}}; the axis map Plinth (y, z) -> ROSS
(x, y) is make_reference.py's, a proper rotation).

Cases: `--cases` lists them; each machine's table (MACHINES in
scripts/ross_unseen_machines.py) says
what each case does. Noise kinds: clean-w1 / clean-h1 (the machine's
noise, 7 digits, no columns), clean-w1c / clean-h1c (with the *_sd noise
columns), clean-dN (no noise, N significant digits, the speed grid shifted
by the seed; clean-dmix: the machine's digits per bearing). unseen-train's
noisy cases are clean-p2 / clean-p2c. Effect cases carry the machine's noise with the *_sd columns;
EFFECT-d3 (where listed) is the same effect without noise at 3 digits.
Effects: a sub-base under one pedestal, a shared base (frame), a worn oil
film (bearings.csv computed for a clearance 15 % smaller than the
machine's), a wrong table scale (the table's stiffness 25 % above the
bearing's), pedestal cross-coupling k_yz = k_zy = r sqrt(k_y k_z), probe
runout (a constant vector on both rel probes), a sensor delay (both rel
probes read Q e^{-i Omega tau}), keyphasor flips (every channel of the
listed bearings negated at three random speeds), one outlier speed (at one
random speed every channel of one bearing gets an error of 0.15 of its RMS
at a random phase, as a transient caught by the tracking filter gives; a
common complex factor on all four channels of one bearing would be
invisible, as the pedestal equations are homogeneous in them).
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
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# the machines (grids, noise laws, cases); FRAME_FOUR is bench_table_combos.py's
from ross_unseen_machines import DEFAULT, FRAME_FOUR, MACHINES  # noqa: E402,F401

CHANNELS = ("rel_y", "rel_z", "ped_y", "ped_z")
RUNOUT_SIZE = 0.2           # of the median |rel| of the bearing
OUTLIER = 0.15             # an outlier's error on each channel, of the channel's RMS
KEYS = ("kyy", "kyz", "kzy", "kzz", "cyy", "cyz", "czy", "czz")


def noise_sd(m, channel, v, speeds):
    """sigma [m] of each phasor of one channel: a fraction of |phasor| plus
    a floor (a fraction of the channel's RMS), per machine, per kind of
    channel (rel / ped) or per channel (rel_y ...) where the machine gives
    them apart; plus "grow" [m/sqrt(Hz)] times sqrt(speed); plus, where the
    law gives them, an absolute floor "abs" [m] and a velocity floor "vel"
    [m/s] (a seismic pick-up's: vel / Omega in displacement, largest at low
    speed) and an acceleration floor "acc" [m/s^2] (an accelerometer's:
    acc / Omega^2) at `speeds` [Hz]."""
    law = m["noise"]
    if channel in law:
        law = law[channel]
    elif "rel" in law and isinstance(law["rel"], dict):
        law = law[channel.split("_")[0]]
    f = np.asarray(speeds)
    return (law["rel"] * np.abs(v) + law["floor"] * math.sqrt(float(np.mean(np.abs(v) ** 2)))
            + law.get("abs", 0.0) + law.get("vel", 0.0) / (2 * math.pi * f) + law.get("grow", 0.0) * np.sqrt(f)
            + law.get("acc", 0.0) / (2 * math.pi * f) ** 2)


def cases_of(machine=DEFAULT):
    """The case names of a machine, in their fixed order (the order seeds
    the random numbers)."""
    m = MACHINES[machine]
    clean = tuple(f"clean-{k}" for k in (m["noisy"], m["noisy"] + "c") + m["digits"])
    effects = tuple(m["effects"])
    field = tuple(f"clean-{k}" for k in m.get("field", ()))  # last: the others' seeds stay
    return clean + effects + (tuple(e + "-d3" for e in effects) if m["d3_effects"] else ()) + field


CASES = cases_of()


def machine_file(machine=DEFAULT):
    """Path of the machine file a user would have (nominal machine)."""
    m = MACHINES[machine]
    return os.path.join(m["data"], m["file"])


def kind(case, machine=DEFAULT):
    """(effect, noise) of a case: noise "w1"/"h1" (the machine's noise),
    with "c" appended the *_sd columns too, "dN" none at N digits."""
    m = MACHINES[machine]
    if case.startswith("clean-"):
        return "clean", case[len("clean-"):]
    if case.endswith("-d3"):
        return case[:-3], "d3"
    return case, m["noisy"] + "c"


def effects_of(case, machine=DEFAULT):
    """The list of effects of a case (empty for a clean case)."""
    effect = kind(case, machine)[0]
    return [] if effect == "clean" else MACHINES[machine]["effects"][effect]


def speeds_of(case, seed, machine=DEFAULT):
    noise = kind(case, machine)[1]
    return MACHINES[machine]["grid"](noise.startswith("d"), seed)


def table_row(b, s):
    """Tabulated coefficients at speed s, linear in speed between rows."""
    rows = b["coefficients"]
    sp = [r["speed_hz"] for r in rows]
    return {k: float(np.interp(s, sp, [r.get(k, 0.0) for r in rows])) for k in KEYS}


def film_row(of, s, clearance):
    K, C = ocvirk(dict(of, clearance=clearance), of["load"], s)
    return {"kyy": K[0][0], "kyz": K[0][1], "kzy": K[1][0], "kzz": K[1][1],
            "cyy": C[0][0], "cyz": C[0][1], "czy": C[1][0], "czz": C[1][1]}


def thermal_factor(thermal, s):
    """The film's viscosity at speed s [Hz] over the design (top speed's)
    one [-] for a "thermal" effect: the effective film temperature's rise
    over the inlet falls as the shear heating, (s / top)^2, so mu grows
    from 1 at the top speed to `ratio` at standstill, exponentially in the
    temperature (ross_unseen_machines.THERMAL_SEVEN)."""
    return thermal["ratio"] ** (1.0 - min(s / thermal["top_hz"], 1.0) ** 2)


def cooling_fraction(cool, speeds):
    """How far the hot end has cooled [-] (0 at the top of the run, 1 at its
    bottom) at each of `speeds` [Hz] of an exponential coast-down: the speed
    falls as exp(-t / T') from `top_hz` to `bottom_hz` in `duration_s`
    [s], so t(f) = duration ln(top / f) / ln(top / bottom); the temperature
    follows a first-order lag of `tau_s` [s]: (1 - exp(-t / tau)) over its
    value at the end of the run (ross_unseen_machines.COOLING_NINE)."""
    f = np.asarray(speeds, dtype=float)
    t = cool["duration_s"] * np.log(cool["top_hz"] / f) / math.log(cool["top_hz"] / cool["bottom_hz"])
    return (1.0 - np.exp(-t / cool["tau_s"])) / (1.0 - math.exp(-cool["duration_s"] / cool["tau_s"]))


def drift_factor(drift, speeds):
    """The pedestal's stiffness over the machine file's [-] at `speeds` [Hz]
    of a "ped_drift" effect: 1 + span (x - 1/2), x the cooling fraction.
    With `run_up` the run's clock goes the other way in speed (a run-up by
    the same exponential law, bottom to top in `duration_s`): the time at
    f is the coast-down's time at the mirrored speed top bottom / f, so the
    drift follows time as before and is reversed in speed."""
    f = np.asarray(speeds, dtype=float)
    if drift.get("run_up"):
        f = drift["top_hz"] * drift["bottom_hz"] / f
    return 1.0 + drift["span"] * (cooling_fraction(drift, f) - 0.5)


def coefficients(spec, speeds, effects):
    """(true, written) coefficients per bearing: lists of dicts per speed."""
    worn = {e[1]: e[2] for e in effects if e[0] == "worn_film"}
    thermal = next((e[1] for e in effects if e[0] == "thermal"), None)
    scale = {e[1]: (e[2], e[3]) for e in effects if e[0] == "table_scale"}
    true, written = {}, {}
    for b in spec["bearings"]:
        name = b["name"]
        if "oil_film" in b:
            of = b["oil_film"]
            if thermal is not None and name in thermal["bearings"]:
                true[name] = [film_row(dict(of, viscosity=of["viscosity"] * thermal_factor(thermal, s)), s,
                                       of["clearance"] * worn.get(name, 1.0)) for s in speeds]
            else:
                true[name] = [film_row(of, s, of["clearance"] * worn.get(name, 1.0)) for s in speeds]
            written[name] = [film_row(of, s, of["clearance"]) for s in speeds]
        else:
            written[name] = [table_row(b, s) for s in speeds]
            true[name] = written[name]
            if name in scale:
                fk, fc = scale[name]
                true[name] = [{k: v * (fk if k[0] == "k" else fc) for k, v in r.items()}
                              for r in written[name]]
    return true, written


def respond(spec, speeds, effects):
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
    true, written = coefficients(spec, speeds, effects)
    frame = next((e[1] for e in effects if e[0] == "frame"), None)
    sub = next((e[1] for e in effects if e[0] == "sub_base"), None)
    cross = {e[1]: e[2] for e in effects if e[0] == "cross"}
    drift = {e[1]["bearing"]: e[1] for e in effects if e[0] == "ped_drift"}
    w = 2 * math.pi * np.asarray(speeds)
    nn = len(x)
    names = [b["name"] for b in spec["bearings"]]
    extra = nn + len(names)  # the next free node number after the pedestals
    base_node = sub_node = None
    if frame is not None:
        base_node, extra = extra, extra + 1
    if sub is not None:
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
        kc = cross[b["name"]] * math.sqrt(p["k_y"] * p["k_z"]) if b["name"] in cross else 0.0
        link = None
        if base_node is not None and b["name"] in frame["bearings"]:
            link = base_node
        if sub_node is not None and b["name"] == sub["bearing"]:
            link = sub_node
        kw = dict(kxx=p["k_y"], kyy=p["k_z"], kxy=kc, kyx=kc, cxx=p.get("c_y", 0.0),
                  cyy=p.get("c_z", 0.0), tag=f"ground_{b['name']}")
        if link is not None:
            kw["n_link"] = link
        if b["name"] in drift:  # the pedestal's stiffness following the run (ped_drift)
            g = drift_factor(drift[b["name"]], speeds)
            kw = dict(kw, frequency=w, kxx=p["k_y"] * g, kyy=p["k_z"] * g,
                      **{k: np.full(len(w), float(kw[k])) for k in ("kxy", "kyx", "cxx", "cyy")})
        elements.append(rs.BearingElement(n=pn, **kw))
    for node, body in ((base_node, frame), (sub_node, sub)):
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


def add_delay(resp, bearing, speeds, tau):
    """Both rel probes of `bearing` read tau [s] late: Q e^{-i Omega tau}."""
    lag = np.exp(-1j * 2 * math.pi * np.asarray(speeds) * tau)
    for c in ("rel_y", "rel_z"):
        resp[bearing][c] = resp[bearing][c] * lag
    return {"tau_s": tau}


def add_ped_delay(resp, bearing, speeds, tau):
    """Both pedestal pick-ups of `bearing` read tau [s] late (their own
    signal conditioner's filters): P e^{-i Omega tau}; the probes on time."""
    lag = np.exp(-1j * 2 * math.pi * np.asarray(speeds) * tau)
    for c in ("ped_y", "ped_z"):
        resp[bearing][c] = resp[bearing][c] * lag
    return {"tau_s": tau}


def add_probe_axes(resp, axes):
    """The proximity probes of `axes["bearings"]` mounted at +-a
    (`angle_deg`) from the vertical and written as they read, not resolved
    to y and z: rel_y holds the probe at -a (towards -z), rel_z the one at
    +a, each reading the displacement along its own axis (cos a y -+ sin a
    z): the rel vector rotated by a (a proper rotation for a = 45 deg)."""
    a = math.radians(axes["angle_deg"])
    for b in axes["bearings"]:
        y, z = resp[b]["rel_y"], resp[b]["rel_z"]
        resp[b]["rel_y"] = math.cos(a) * y - math.sin(a) * z
        resp[b]["rel_z"] = math.sin(a) * y + math.cos(a) * z
    return {"angle_deg": axes["angle_deg"]}


def add_runout_drift(resp, drift, speeds):
    """probe_runout's vector on both rel probes of `drift["bearing"]` [m] at
    the top of the run, changing with the journal's temperature: times
    (1 + growth x) e^{i turn x}, x the cooling fraction at each speed."""
    b = drift["bearing"]
    x = cooling_fraction(drift, speeds)
    top = {c: np.array(resp[b][c]) for c in ("rel_y", "rel_z")}
    params = add_runout(resp, b)
    factor = (1.0 + drift["growth"] * x) * np.exp(1j * math.radians(drift["turn_deg"]) * x)
    for c in ("rel_y", "rel_z"):
        resp[b][c] = top[c] + (resp[b][c] - top[c]) * factor
    return dict(params, growth=drift["growth"], turn_deg=drift["turn_deg"])


def add_probe_gain(resp, gain):
    """One channel (`gain["channel"]` of `gain["bearing"]`) read with a
    sensitivity `gain["gain"]` times the one assumed (a calibration error:
    the signal scaled, its phase right)."""
    b, c = gain["bearing"], gain["channel"]
    resp[b][c] = resp[b][c] * gain["gain"]
    return {f"{c}_gain": gain["gain"]}


def speed_lag_hz(lag):
    """How far [Hz] the speed column of a "speed_lag" effect reads above the
    true speed in a run-down at `rate_hz_per_s`: the monitoring system's
    speed is the keyphasor's pulse rate through a first-order filter of
    time constant `lag_s` [s], which lags a ramp by lag_s, so the speed
    stamped on a vector is that of lag_s earlier."""
    return lag["rate_hz_per_s"] * lag["lag_s"]


def correlated(w, corr):
    """White complex draws `w` (along the run) made an AR(1) of the same
    marginal sigma: n_j = rho n_{j-1} + sqrt(1 - rho^2) w_j, rho =
    exp(-dt / tau) with dt = step_hz / rate_hz_per_s [s] between stored
    vectors and tau = filter_tau_s [s] (a "corr_noise" effect)."""
    rho = math.exp(-corr["step_hz"] / corr["rate_hz_per_s"] / corr["filter_tau_s"])
    out = np.empty_like(w)
    out[0] = w[0]
    for j in range(1, len(w)):
        out[j] = rho * out[j - 1] + math.sqrt(1.0 - rho * rho) * w[j]
    return out


def sweep_speeds(speeds, sweep):
    """The speeds [Hz] the revolutions of each vector span in a coast-down
    at a constant deceleration a = `rate_hz_per_s`: a block of N =
    `revolutions` revolutions whose mean speed is the logged one, f_j,
    lasts N / f_j and spans f_j +- a N / (2 f_j); sampled at `points`
    equal steps of the revolution count (the filter weighs each revolution
    alike): f^2 = f_hi^2 - 2 a theta. Returns an array (len(speeds),
    points)."""
    a, n, k = sweep["rate_hz_per_s"], sweep["revolutions"], sweep["points"]
    out = []
    for f in np.asarray(speeds, dtype=float):
        hi = f + a * n / (2 * f)
        theta = (np.arange(k) + 0.5) * n / k
        out.append(np.sqrt(np.maximum(hi * hi - 2 * a * theta, 1e-6)))
    return np.array(out)


def swept(spec, speeds, physical, sweep):
    """respond()'s phasors as a tracking filter reads them during a fast
    coast-down (`sweep`: sweep_speeds): each the mean of the steady-state
    phasors at the speeds its revolutions span (the quasi-static part of
    the sweep; the transient, a resonance's ring-down lagging the speed,
    is not modelled). The table written is the logged speeds'."""
    sub = sweep_speeds(speeds, sweep)
    grid, where = np.unique(sub.ravel(), return_inverse=True)  # ROSS wants rising speeds
    resp, _ = respond(spec, grid, physical)
    written = coefficients(spec, speeds, physical)[1]
    return {b: {c: np.asarray(v)[where].reshape(sub.shape).mean(axis=1) for c, v in ch.items()}
            for b, ch in resp.items()}, written


def sig(v, digits):
    return f"{v:.{digits - 1}e}"


def physical_detail(effect, spec):
    """truth.json's effect_details entry of an effect ROSS simulates."""
    what = effect[0]
    if what == "frame":
        return {"name": "foundation_coupling", "bearing": effect[1]["bearings"][0], "parameters": {}}
    if what == "sub_base":
        return {"name": "pedestal_sub_base", "bearing": effect[1]["bearing"],
                "parameters": {k: v for k, v in effect[1].items() if k != "bearing"}}
    if what == "worn_film":
        return {"name": "bearing_coefficients", "bearing": effect[1],
                "parameters": {"clearance_ratio": effect[2]}}
    if what == "table_scale":
        return {"name": "bearing_coefficients", "bearing": effect[1],
                "parameters": {"k_scale": effect[2], "c_scale": effect[3]}}
    if what == "thermal":
        return {"name": "oil_thermal", "bearing": ",".join(effect[1]["bearings"]),
                "parameters": {"viscosity_ratio_at_rest": effect[1]["ratio"], "top_hz": effect[1]["top_hz"]}}
    if what == "ped_drift":
        p = next(b for b in spec["bearings"] if b["name"] == effect[1]["bearing"])["pedestal"]
        lo, hi = drift_factor(effect[1], [effect[1]["top_hz"], effect[1]["bottom_hz"]])
        return {"name": "pedestal_drift", "bearing": effect[1]["bearing"],
                "parameters": {"k_y_top": p["k_y"] * lo, "k_y_bottom": p["k_y"] * hi,
                               "k_z_top": p["k_z"] * lo, "k_z_bottom": p["k_z"] * hi,
                               **{k: float(v) for k, v in effect[1].items() if k != "bearing"}}}
    if what == "sweep":
        return {"name": "sweep_average", "bearing": "",
                "parameters": {k: float(v) for k, v in effect[1].items()}}
    if what == "cross":
        p = next(b for b in spec["bearings"] if b["name"] == effect[1])["pedestal"]
        return {"name": "pedestal_cross_coupling", "bearing": effect[1],
                "parameters": {"k_yz": effect[2] * math.sqrt(p["k_y"] * p["k_z"])}}
    raise ValueError(what)


# formats.md's effect names: truth.json's `effects` lists only these (the
# data contract); a departure no library effect names stays in
# `effect_details` under its own name. The oil's viscosity following the
# speed is a bearing table that does not describe the bearing in the machine
# ("temperature off"), so it is listed as `bearing_coefficients`; a probe
# runout that changes with the journal's temperature is a runout
# (`probe_runout`, the library's being constant).
LIBRARY = ("pedestal_damping", "structural_damping", "pedestal_cross_coupling", "pedestal_mass_anisotropy",
           "probe_runout", "sensor_delay", "foundation_coupling", "pedestal_sub_base", "bearing_coefficients")
AS_LIBRARY = {"oil_thermal": "bearing_coefficients", "probe_runout_drift": "probe_runout"}


def library_names(details):
    """truth.json's `effects`: the formats.md names of the effects in `details`, in order."""
    names = (AS_LIBRARY.get(d["name"], d["name"]) for d in details)
    return [n for n in names if n in LIBRARY]


_CACHE = {}


def make(out, case, seed, machine=DEFAULT):
    """Writes one run directory; returns its truth dict."""
    m = MACHINES[machine]
    with open(machine_file(machine), "rb") as f:
        spec = tomllib.load(f)
    speeds = speeds_of(case, seed, machine)
    effect, noise_kind = kind(case, machine)
    effects = effects_of(case, machine)
    physical = [e for e in effects if e[0] in ("frame", "sub_base", "worn_film", "table_scale", "cross",
                                               "thermal", "ped_drift")]
    sweep = next((e[1] for e in effects if e[0] == "sweep"), None)
    key = (machine, repr(physical), repr(sweep), tuple(speeds))
    if key not in _CACHE:  # ROSS's response depends on the physical effects and grid only
        _CACHE[key] = respond(spec, speeds, physical) if sweep is None else swept(spec, speeds, physical, sweep)
    resp, written = _CACHE[key]
    resp = {b: dict(v) for b, v in resp.items()}
    names = [b["name"] for b in spec["bearings"]]
    details = []
    for e in effects:
        if e[0] == "runout":
            details.append({"name": "probe_runout", "bearing": e[1], "parameters": add_runout(resp, e[1])})
        elif e[0] == "delay":
            details.append({"name": "sensor_delay", "bearing": e[1],
                            "parameters": add_delay(resp, e[1], speeds, e[2])})
        elif e[0] == "ped_delay":
            details.append({"name": "sensor_delay", "bearing": e[1],
                            "parameters": add_ped_delay(resp, e[1], speeds, e[2])})
        elif e[0] == "probe_axes":
            details.append({"name": "probe_axes", "bearing": ",".join(e[1]["bearings"]),
                            "parameters": add_probe_axes(resp, e[1])})
        elif e[0] == "speed_lag":
            details.append({"name": "speed_lag", "bearing": "",
                            "parameters": {"lag_hz": speed_lag_hz(e[1]), **e[1]}})
        elif e[0] == "runout_drift":
            details.append({"name": "probe_runout_drift", "bearing": e[1]["bearing"],
                            "parameters": add_runout_drift(resp, e[1], speeds)})
        elif e[0] == "probe_gain":
            details.append({"name": "probe_gain", "bearing": e[1]["bearing"],
                            "parameters": add_probe_gain(resp, e[1])})
        elif e[0] == "corr_noise":
            details.append({"name": "correlated_noise", "bearing": "", "parameters": dict(e[1])})
        elif e in physical or e[0] == "sweep":
            details.append(physical_detail(e, spec))
    rng = np.random.default_rng(m["rng"] + 101 * cases_of(machine).index(case) + seed)
    noisy = not noise_kind.startswith("d")
    columns = noise_kind.endswith("c")
    if noisy:
        digits = {b: 7 for b in names}
    elif noise_kind == "dmix":
        digits = m["mixed_digits"]
    else:
        digits = {b: int(noise_kind[1:]) for b in names}
    corr = next((e[1] for e in effects if e[0] == "corr_noise"), None)
    data, sd = {}, {}
    for b in names:
        for c in CHANNELS:
            v = resp[b][c]
            if noisy:
                s = noise_sd(m, c, v, speeds)
            else:
                s = np.zeros(len(v))
            sd[(b, c)] = s
            w = rng.standard_normal(len(v)) + 1j * rng.standard_normal(len(v))
            if corr is not None:
                w = correlated(w, corr)
            noise = w * s / math.sqrt(2)
            data[(b, c)] = v + noise
    for e in effects:
        if e[0] == "flips":
            idx = sorted(rng.choice(np.arange(3, len(speeds) - 3), size=3, replace=False).tolist())
            flipped = [float(speeds[i]) for i in idx]
            for b in e[1]:
                for c in CHANNELS:
                    data[(b, c)][idx] *= -1
                details.append({"name": "keyphasor_flip", "bearing": b,
                                "parameters": {f"speed_{k}_hz": s for k, s in enumerate(flipped)}})
        elif e[0] == "outlier":
            i = int(rng.choice(np.arange(3, len(speeds) - 3)))
            for c in CHANNELS:
                rms = math.sqrt(float(np.mean(np.abs(resp[e[1]][c]) ** 2)))
                data[(e[1], c)][i] += OUTLIER * rms * np.exp(2j * math.pi * rng.random())
            details.append({"name": "outlier_speed", "bearing": e[1],
                            "parameters": {"speed_0_hz": float(speeds[i])}})
    lag = next((e[1] for e in effects if e[0] == "speed_lag"), None)
    if lag is not None:  # the speed column (and the table written there) read high
        speeds = speeds + speed_lag_hz(lag)
        written = coefficients(spec, speeds, physical)[1]
    if noise_kind == "vel":
        write_field(out, speeds, names, data, written)
    else:
        write(out, speeds, names, data, sd if columns else None, digits, written,
              table_rows(spec) if m.get("table_rows") else None)
    truth = {"pedestals": nominal_truth(machine),
             "effects": library_names(details),
             "effect_details": details}
    bases = []
    for e in effects:
        if e[0] == "frame":
            bases.append(dict(e[1], eta=0.0))
        if e[0] == "sub_base":
            bases.append({"name": f"{e[1]['bearing']}-sub-base", "bearings": [e[1]["bearing"]], "eta": 0.0,
                          **{k: v for k, v in e[1].items() if k != "bearing"}})
    if bases:
        truth["bases"] = bases
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
        f.write("\n")
    return truth


def nominal_truth(machine=DEFAULT):
    """The machine file's pedestals, as truth.json lists them."""
    with open(machine_file(machine), "rb") as f:
        spec = tomllib.load(f)
    return [{"bearing": b["name"], "k_y": b["pedestal"]["k_y"], "k_z": b["pedestal"]["k_z"],
             "m": b["pedestal"]["m"], "c_y": b["pedestal"].get("c_y", 0.0),
             "c_z": b["pedestal"].get("c_z", 0.0)} for b in spec["bearings"]]


def table_rows(spec):
    """bearings.csv's rows as the machine file tabulates them: (speed [Hz],
    bearing, row) at each table's own speeds, where every bearing is a
    table (a reader interpolates linearly between rows, as table_row
    does, so these give the same coefficients at every speed in range as
    rows at the run's speeds would, in a file a fraction of the size)."""
    rows = []
    for b in spec["bearings"]:
        if "coefficients" not in b:
            raise ValueError(f"{b['name']}: table_rows needs every bearing tabulated")
        rows += [(r["speed_hz"], b["name"], {k: float(r.get(k, 0.0)) for k in KEYS}) for r in b["coefficients"]]
    return sorted(rows, key=lambda r: r[0])


def write(out, speeds, names, data, sd, digits, written, rows=None):
    """measurements.csv (sd: the *_sd columns, or None; digits: significant
    digits per bearing) and bearings.csv (at the run's speeds, or `rows`:
    table_rows's)."""
    os.makedirs(out, exist_ok=True)
    fmt = lambda s: f"{s:.6g}"  # noqa: E731
    with open(os.path.join(out, "measurements.csv"), "w") as f:
        head = "speed_hz,bearing," + ",".join(f"{c}_re,{c}_im" for c in CHANNELS)
        if sd is not None:
            head += "," + ",".join(f"{c}_sd" for c in CHANNELS)
        f.write(head + "\n")
        for j, s in enumerate(speeds):
            for b in names:
                row = [fmt(s), b]
                for c in CHANNELS:
                    q = data[(b, c)][j]
                    row += [sig(q.real, digits[b]), sig(q.imag, digits[b])]
                if sd is not None:
                    row += [sig(sd[(b, c)][j], 4) for c in CHANNELS]
                f.write(",".join(row) + "\n")
    with open(os.path.join(out, "bearings.csv"), "w") as f:
        f.write("speed_hz,bearing," + ",".join(KEYS) + "\n")
        if rows is not None:
            for s, b, r in rows:
                f.write(",".join([fmt(s), b] + [sig(r[k], 10) for k in KEYS]) + "\n")
            return
        for j, s in enumerate(speeds):
            for b in names:
                f.write(",".join([fmt(s), b] + [sig(written[b][j][k], 10) for k in KEYS]) + "\n")


# A field instrument's transducers (formats.md "A 1X vector table"):
# proximity probes at 45 deg either side of the vertical in um pp, seismic
# pick-ups at 0 and 90 deg in mm/s 0-pk (velocity), phase as lag, speed in
# rpm; amplitudes written to 3 significant digits, phases to 0.1 deg.
FIELD_TRANSDUCERS = (("rel", 45.0, "um pp"), ("rel", -45.0, "um pp"),
                     ("ped", 0.0, "mm/s pk"), ("ped", 90.0, "mm/s pk"))


def write_field(out, speeds, names, data, written):
    """OUT/field/: vectors.csv (the 1X vector table), layout.toml and
    bearings.csv, for `plinth import OUT/field/vectors.csv --layout
    OUT/field/layout.toml --bearings OUT/field/bearings.csv --out OUT`.
    Each transducer reads the displacement along its axis, cos(a) y +
    sin(a) z; a pick-up reads its velocity i Omega X; a reading of
    amplitude A and lag phi is the phasor A e^{-i phi}."""
    field = os.path.join(out, "field")
    os.makedirs(field, exist_ok=True)
    w = 2 * math.pi * np.asarray(speeds)
    cols, layout = [], ['phase = "lag"', 'speed = { column = "Speed rpm", unit = "rpm" }', ""]
    for b in names:
        for q, a, unit in FIELD_TRANSDUCERS:
            y, z = data[(b, f"{q}_y")], data[(b, f"{q}_z")]
            x = math.cos(math.radians(a)) * y + math.sin(math.radians(a)) * z
            if unit == "um pp":
                amp = 2e6 * np.abs(x)
            else:
                x = 1j * w * x
                amp = 1e3 * np.abs(x)
            lag = np.mod(-np.degrees(np.angle(x)), 360.0)
            name = f"{b} {q} {a:+.0f}"
            cols.append((f"{name} amp", [f"{v:.3g}" for v in amp]))
            cols.append((f"{name} ph", [f"{v:.1f}" for v in lag]))
            layout += ["[[transducer]]", f'bearing = "{b}"', f'quantity = "{q}"', f"angle_deg = {a}",
                       f'amplitude = {{ column = "{name} amp", unit = "{unit}" }}',
                       f'phase = {{ column = "{name} ph" }}', ""]
    with open(os.path.join(field, "vectors.csv"), "w") as f:
        f.write("Speed rpm," + ",".join(c for c, _ in cols) + "\n")
        for j, s in enumerate(speeds):
            f.write(f"{60 * s:.2f}," + ",".join(v[j] for _, v in cols) + "\n")
    with open(os.path.join(field, "layout.toml"), "w") as f:
        f.write("\n".join(layout))
    with open(os.path.join(field, "bearings.csv"), "w") as f:
        f.write("speed_hz,bearing," + ",".join(KEYS) + "\n")
        for j, s in enumerate(speeds):
            for b in names:
                f.write(",".join([f"{s:.6g}", b] + [sig(written[b][j][k], 10) for k in KEYS]) + "\n")


TILTING_PAD_SPEEDS = (12.0, 20.0, 30.0, 50.0, 70.0, 90.0, 120.0)  # [Hz], unseen-flex's table rows


def tilting_pad_eccentricity(f):
    """unseen-flex's operating line: the journal's eccentricity ratio [-] at
    f [Hz], falling with speed (0.54 at 12 Hz, 0.45 at 30 Hz, 0.23 at
    120 Hz); below 30 Hz a flatter law, so the low-speed matrices stay
    positive definite."""
    return 0.35 * (50.0 / f) ** (0.3 if f < 30.0 else 0.5)


def tilting_pad_table():
    """unseen-flex's bearing table rows (TOML) from ROSS's own THD
    TiltingPad element, one solve per speed (about 1 s each), mapped to
    Plinth's axes as respond() maps them (ROSS x, y = Plinth y, z)."""
    from ross.bearings.tilting_pad import TiltingPad
    from ross.units import Q_
    for f in TILTING_PAD_SPEEDS:
        b = TiltingPad(n=1, frequency=Q_([60 * f], "RPM"), equilibrium_type="match_eccentricity",
                       journal_diameter=101.6e-3, radial_clearance=74.9e-6, pad_thickness=12.7e-3,
                       pivot_angle=Q_([18, 90, 162, 234, 306], "deg"), pad_arc=Q_([60] * 5, "deg"),
                       pad_axial_length=Q_([50.8e-3] * 5, "m"), pre_load=[0.5] * 5, offset=[0.5] * 5,
                       lubricant="ISOVG32", oil_supply_temperature=Q_(40, "degC"),
                       eccentricity=tilting_pad_eccentricity(f), attitude_angle=Q_(287.5, "deg"),
                       load=[8.8405e+02, -2.6704e+03], nx=15, nz=10)
        v = {k: float(getattr(b, r)[0]) for k, r in zip(KEYS, ("kxx", "kxy", "kyx", "kyy",
                                                              "cxx", "cxy", "cyx", "cyy"))}
        print(f"  {{ speed_hz = {f:.1f}, " + ", ".join(f"{k} = {v[k]:.4e}" for k in KEYS) + " },")


def read_phasors(run):
    """{(speed text, bearing, channel): complex} of a run's measurements.csv."""
    import csv
    with open(os.path.join(run, "measurements.csv")) as f:
        return {(r["speed_hz"], r["bearing"], c): complex(float(r[c + "_re"]), float(r[c + "_im"]))
                for r in csv.DictReader(f) for c in CHANNELS}


def compare(a, b):
    """Worst |a - b| per bearing and channel over the speeds both runs have,
    relative to that channel's peak |b|; printed, the worst returned."""
    pa, pb = read_phasors(a), read_phasors(b)
    common = sorted(set(pa) & set(pb))
    if not common:
        sys.exit(f"{a} and {b}: no speed in common")
    worst = 0.0
    for bearing in sorted({k[1] for k in common}):
        for c in CHANNELS:
            keys = [k for k in common if k[1] == bearing and k[2] == c]
            peak = max(abs(pb[k]) for k in keys)
            d = max(abs(pa[k] - pb[k]) for k in keys) / peak
            worst = max(worst, d)
            print(f"{bearing} {c}: worst |difference| {100 * d:.3f} % of the peak ({len(keys)} speeds)")
    print(f"worst {100 * worst:.3f} %")
    return worst


def main():
    args = sys.argv[1:]
    if args == ["--tilting-pad"]:
        tilting_pad_table()
        return
    if args[:1] == ["--compare"] and len(args) == 3:
        compare(args[1], args[2])
        return
    machine = DEFAULT
    if args[:1] == ["--machine"] and len(args) >= 2 and args[1] in MACHINES:
        machine, args = args[1], args[2:]
    cases = cases_of(machine)
    if args == ["--cases"]:
        print("\n".join(cases))
    elif args == ["--repo"]:
        for case in MACHINES[machine]["repo"]:
            make(os.path.join(MACHINES[machine]["data"], case), case, 1, machine)
            print(f"{case}: written")
    elif len(args) >= 3 and all(c in cases for c in args[1].split(",")):
        for seed in args[2:]:  # CASE,CASE...: one process, ROSS's responses cached
            for case in args[1].split(","):
                make(os.path.join(args[0], f"{case}-{seed}"), case, int(seed), machine)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
