"""The machines of scripts/ross_unseen.py: per machine its file and data
directory, speed grid, noise law, random-number base, cases (effects) and
stored runs, and the speed grids and bodies (sub-bases, frames) they use.
Split from ross_unseen.py (session 38) along this line: what each machine
is here, how a run directory is made there. Frequencies in Hz, masses in
kg, stiffnesses in N/m, damping in N s/m, delays in s."""
import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

def uniform_grid(first, last, step):
    """Speeds first..last [Hz] in steps of `step`, shifted 0.137 Hz per
    seed in the digit cases."""
    def speeds(shifted, seed):
        shift = 0.137 * (seed - 1) if shifted else 0.0
        n = int(round((last - first) / step)) + 1
        return np.round(first + shift + step * np.arange(n), 4)
    return speeds


def coast_down_grid(top, bottom, n):
    """A windage-braked coast-down sampled every few revolutions: n speeds
    from `top` down to `bottom` [Hz] in a constant ratio (listed rising),
    the phase of the sampling shifted by the seed in the digit cases."""
    ratio = (bottom / top) ** (1.0 / (n - 1))
    def speeds(shifted, seed):
        frac = (0.37 * (seed - 1)) % 1.0 if shifted else 0.0
        return np.round(np.sort(top * ratio ** (np.arange(n) + frac)), 3)
    return speeds


def run_up_grid(bottom, top, n, skipped):
    """A run-up at constant acceleration sampled every few revolutions:
    Omega^2 grows by the same step per sample, so n speeds from `bottom` to
    `top` [Hz] spaced ever closer at high speed; the speeds inside the band
    `skipped` = (lo, hi) [Hz] are missing (the operator drove fast through
    it); the phase of the sampling shifted by the seed in the digit cases."""
    def speeds(shifted, seed):
        frac = (0.37 * (seed - 1)) % 1.0 if shifted else 0.0
        sq = bottom**2 + (top**2 - bottom**2) * (np.arange(n) + frac) / (n - 1)
        s = np.round(np.sqrt(sq), 3)
        return s[(s < skipped[0]) | (s > skipped[1])]
    return speeds


def run_down_grid(top, bottom, n, gap, seed=4_404):
    """A run-down recorded by an instrument that samples when it can: n
    speeds from `top` down to `bottom` [Hz] (listed rising) with uneven
    steps (each step 0.3-1.7 of the mean, fixed by `seed`, the same in every
    run), the speeds inside the band `gap` = (lo, hi) [Hz] lost (a recorder
    drop-out); the sampling shifted by a fraction of a mean step per seed in
    the digit cases."""
    u = np.random.default_rng(seed).uniform(0.3, 1.7, n - 1)
    p = np.concatenate([[0.0], np.cumsum(u)]) / np.sum(u)
    def speeds(shifted, s):
        frac = (0.37 * (s - 1)) % 1.0 if shifted else 0.0
        q = np.clip(p + frac * np.mean(u) / np.sum(u), 0.0, 1.0)
        v = np.unique(np.round(bottom + (top - bottom) * q, 3))
        return v[(v < gap[0]) | (v > gap[1])]
    return speeds


SUB_BASE_FOUR = {"bearing": "B3", "m_y": 180.0, "m_z": 160.0, "k_y": 2.4e7, "k_z": 2.0e7,
                 "c_y": 2500.0, "c_z": 2000.0}
FRAME_FOUR = {"name": "frame", "bearings": ["B1", "B2"], "m_y": 350.0, "m_z": 350.0,
              "k_y": 1.6e7, "k_z": 2.2e7, "c_y": 3000.0, "c_z": 2500.0}
SUB_BASE_OVERHUNG = {"bearing": "B1", "m_y": 140.0, "m_z": 140.0, "k_y": 3.0e7, "k_z": 1.0e7,
                     "c_y": 3000.0, "c_z": 1500.0}
SKID_OVERHUNG = {"name": "skid", "bearings": ["B1", "B2"], "m_y": 500.0, "m_z": 500.0,
                 "k_y": 6.0e7, "k_z": 2.0e7, "c_y": 4000.0, "c_z": 2000.0}

SUB_BASE_TRAIN = {"bearing": "B2", "m_y": 150.0, "m_z": 150.0, "k_y": 2.0e8, "k_z": 1.2e8,
                  "c_y": 5000.0, "c_z": 3000.0}
FRAME_TRAIN = {"name": "baseplate", "bearings": ["B2", "B3"], "m_y": 400.0, "m_z": 400.0,
               "k_y": 1.2e8, "k_z": 6.0e7, "c_y": 6000.0, "c_z": 4000.0}

SUB_BASE_FLEX = {"bearing": "B1", "m_y": 600.0, "m_z": 600.0, "k_y": 4.0e8, "k_z": 3.0e8,
                 "c_y": 2.0e4, "c_z": 1.5e4}
FRAME_FLEX = {"name": "bedplate", "bearings": ["B1", "B2"], "m_y": 900.0, "m_z": 900.0,
              "k_y": 3.0e8, "k_z": 1.5e8, "c_y": 2.0e4, "c_z": 1.2e4}

# Per machine: its file and data directory, speed grid, noise (sigma = rel
# |phasor| + floor RMS of the channel), the seed base of its random numbers,
# its cases (effect case: list of effects, applied in order) and the runs
# kept in the repository (seed 1).
MACHINES = {
    "unseen-four": {
        "data": os.path.join(ROOT, "tests", "data", "ross-unseen"),
        "file": "unseen-four.toml",
        "grid": uniform_grid(6.0, 126.0, 1.25),
        "noise": {"rel": 0.0, "floor": 0.01},
        "noisy": "w1",
        "digits": ("d3",),
        "rng": 17_000,
        "effects": {
            "sub-base": [("sub_base", SUB_BASE_FOUR)],
            "table": [("worn_film", "B2", 1.0 / 0.85)],
            "cross": [("cross", "B4", 0.2)],
            "runout": [("runout", "B3")],
            "flips": [("flips", ["B1"])],
            "base-runout": [("frame", FRAME_FOUR), ("runout", "B2")],
        },
        "d3_effects": True,
        "repo": ("clean-w1c", "clean-d3", "sub-base", "sub-base-d3", "table", "cross", "runout",
                 "flips", "base-runout-d3"),
    },
    "unseen-overhung": {
        "data": os.path.join(ROOT, "tests", "data", "ross-unseen-2"),
        "file": "unseen-overhung.toml",
        "grid": coast_down_grid(150.0, 8.0, 120),
        "noise": {"rel": 0.01, "floor": 0.001},
        "noisy": "h1",
        "digits": ("d3", "d2", "d12"),
        "rng": 23_000,
        "effects": {
            "sub-base": [("sub_base", SUB_BASE_OVERHUNG)],
            "table-film": [("worn_film", "B2", 1.0 / 0.85)],
            "table-scale": [("table_scale", "B1", 1.0 / 1.25, 1.0)],
            "cross": [("cross", "B1", 0.2)],
            "runout": [("runout", "B2")],
            "delay": [("delay", "B1", 150e-6)],
            "flips": [("flips", ["B1", "B2"])],
            "outlier": [("outlier", "B2")],
            "base-runout-delay": [("frame", SKID_OVERHUNG), ("runout", "B1"), ("delay", "B2", 150e-6)],
            "cross-runout": [("cross", "B2", 0.2), ("runout", "B1")],
        },
        "d3_effects": False,
        "repo": ("clean-h1", "clean-h1c", "clean-d3", "sub-base", "table-film", "table-scale", "cross", "runout",
                 "delay", "flips", "outlier", "base-runout-delay", "cross-runout"),
    },
    "unseen-train": {
        "data": os.path.join(ROOT, "tests", "data", "ross-unseen-3"),
        "file": "unseen-train.toml",
        "grid": run_up_grid(5.0, 85.0, 150, (38.0, 46.0)),
        # pedestal pick-ups: 2 % of |phasor|, no floor; proximity probes: a
        # constant floor of 0.5 % of the channel's RMS
        "noise": {"rel": {"rel": 0.0, "floor": 0.005}, "ped": {"rel": 0.02, "floor": 0.0}},
        "noisy": "p2",
        "digits": ("d3", "dmix", "d12"),
        "mixed_digits": {"B1": 2, "B2": 3, "B3": 4},
        "rng": 24_000,
        "effects": {
            "sub-base": [("sub_base", SUB_BASE_TRAIN)],
            "table-film": [("worn_film", "B2", 1.0 / 0.85)],
            "table-scale": [("table_scale", "B3", 1.0 / 1.25, 1.0)],
            "cross": [("cross", "B3", 0.2)],
            "runout": [("runout", "B1")],
            "delay": [("delay", "B2", 150e-6)],
            "flips": [("flips", ["B1", "B2", "B3"])],
            "outlier": [("outlier", "B3")],
            "base-runout": [("frame", FRAME_TRAIN), ("runout", "B1")],
            "cross-delay": [("cross", "B2", 0.2), ("delay", "B3", 150e-6)],
        },
        "d3_effects": False,
        "repo": ("clean-p2", "clean-p2c", "clean-dmix", "sub-base", "table-film", "table-scale", "cross", "runout",
                 "delay", "outlier", "base-runout"),
    },
}
MACHINES["unseen-flex"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-4"),
    "file": "unseen-flex.toml",
    "grid": run_down_grid(110.0, 12.0, 110, (55.0, 61.0)),
    # per kind of sensor, the sensor's own floor, not a fraction of the
    # signal: proximity probes sigma = 0.5 % of |phasor| + 0.05 um; seismic
    # pick-ups 1 % of |phasor| + a velocity floor of 1 um/s (1.3e-8 m at
    # 12 Hz): B1's pick-ups on the stiff block read near it at low speed
    "noise": {"rel": {"rel": 0.005, "floor": 0.0, "abs": 5e-8},
              "ped": {"rel": 0.01, "floor": 0.0, "vel": 1e-6}},
    "noisy": "n1",
    "digits": ("d2", "d3", "d12"),
    "rng": 26_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_FLEX)],
        "table-scale": [("table_scale", "B2", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B2", 0.2)],
        "runout": [("runout", "B1")],
        "delay": [("delay", "B2", 150e-6)],
        "flips": [("flips", ["B1"])],
        "outlier": [("outlier", "B2")],
        "delay-runout": [("delay", "B1", 150e-6), ("runout", "B2")],
        "base": [("frame", FRAME_FLEX)],
    },
    # clean-vel: the machine's noise, written as a field instrument's 1X
    # vector table (FIELD_LAYOUT) for `plinth import`
    "field": ("vel",),
    "d3_effects": False,
    "repo": ("clean-n1", "clean-vel", "clean-d2", "sub-base", "cross", "runout", "delay", "delay-runout", "base"),
}
SUB_BASE_FIVE = {"bearing": "B2", "m_y": 250.0, "m_z": 250.0, "k_y": 1.5e8, "k_z": 6.0e7,
                 "c_y": 4000.0, "c_z": 2000.0}
FRAME_FIVE = {"name": "skid", "bearings": ["B1", "B2"], "m_y": 600.0, "m_z": 600.0,
              "k_y": 2.0e8, "k_z": 8.0e7, "c_y": 8000.0, "c_z": 4000.0}
MACHINES["unseen-five"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-5"),
    "file": "unseen-five.toml",
    # a coarse run-down table: one speed logged every 1.5 Hz, 56.1 Hz down
    # to 9.6 Hz (32 speeds), about as coarse as the lightly damped peaks are
    # wide; the top speed below the oil whip onset (59 Hz: ROSS's log dec of
    # the 29 Hz mode crosses zero there, B1's lightly loaded film driving it)
    "grid": uniform_grid(9.6, 56.1, 1.5),
    # noisier than the others: 3 % of |phasor| plus a floor of 0.3 % of the
    # channel's RMS on every channel
    "noise": {"rel": 0.03, "floor": 0.003},
    "noisy": "n3",
    "digits": ("d3", "d12"),
    "rng": 27_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_FIVE)],
        "table-film": [("worn_film", "B1", 1.0 / 0.85)],
        "table-scale": [("table_scale", "B2", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B1", 0.2)],
        "runout": [("runout", "B2")],
        "delay": [("delay", "B1", 150e-6)],
        "flips": [("flips", ["B1", "B2"])],
        "outlier": [("outlier", "B1")],
        "base": [("frame", FRAME_FIVE)],
    },
    "d3_effects": False,
    "repo": ("clean-n3", "clean-n3c", "cross", "sub-base"),
}
DEFAULT = "unseen-four"
# unseen-six (session 45) is tests/data/ross-unseen-6/unseen-six.toml: a fan
# line shaft on three bearings, B1 and B3 rolling-element tables (nearly
# constant, y stiffer than z, no cross-coupling, little damping), B2 a short
# sleeve steady bearing, the 140 kg wheel between B2 and B3; light soft
# pedestals (30-60 kg, k_y/k_z about 6) whose horizontal resonances (45, 22,
# 38 Hz) and B2's vertical one (52 Hz) lie inside the run-down; the rotor's
# own modes at 15, 25, 34, 42-44 and 46-48 Hz (ROSS, log dec 0.04-0.07).
SUB_BASE_SIX = {"bearing": "B2", "m_y": 80.0, "m_z": 80.0, "k_y": 1.5e7, "k_z": 5.0e6,
                "c_y": 1500.0, "c_z": 600.0}
FRAME_SIX = {"name": "fan-frame", "bearings": ["B2", "B3"], "m_y": 250.0, "m_z": 250.0,
             "k_y": 3.0e7, "k_z": 1.2e7, "c_y": 3000.0, "c_z": 1500.0}
MACHINES["unseen-six"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-6"),
    "file": "unseen-six.toml",
    # a run-down logged unevenly (steps 0.3-1.7 of the mean, fixed), 62 Hz
    # down to 4 Hz, 58 speeds, no drop-out: through every horizontal
    # pedestal resonance (22, 38, 45 Hz) and B2's vertical one (52 Hz)
    "grid": run_down_grid(62.0, 4.0, 58, (0.0, 0.0), seed=6_606),
    # per channel, each sensor its own floor (a fraction of that channel's
    # RMS: B-side probes read 0.3 %/1 % (y/z: the z probe sits on a rough
    # band), pick-ups 0.5 %/2 % (z: the soft horizontal frame rattles)),
    # 0.5 % of |phasor|, and a broadband term a tracking filter of a fixed
    # number of revolutions passes: its bandwidth grows with speed, so
    # sigma grows as sqrt(speed) ("grow" [m/sqrt(Hz)])
    "noise": {"rel_y": {"rel": 0.005, "floor": 0.003, "grow": 5e-10},
              "rel_z": {"rel": 0.005, "floor": 0.01, "grow": 5e-10},
              "ped_y": {"rel": 0.005, "floor": 0.005, "grow": 1e-8},
              "ped_z": {"rel": 0.005, "floor": 0.02, "grow": 1e-8}},
    "noisy": "s1",
    "digits": ("d2", "dmix", "d12"),
    "mixed_digits": {"B1": 4, "B2": 2, "B3": 3},
    "rng": 36_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_SIX)],
        "table-film": [("worn_film", "B2", 1.0 / 0.85)],
        "table-scale": [("table_scale", "B3", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B1", 0.2)],
        "runout": [("runout", "B3")],
        "delay": [("delay", "B2", 150e-6)],
        "flips": [("flips", ["B1", "B3"])],
        "outlier": [("outlier", "B1")],
        "base": [("frame", FRAME_SIX)],
        "base-delay": [("frame", FRAME_SIX), ("delay", "B1", 150e-6)],
        "cross-runout": [("cross", "B3", 0.2), ("runout", "B1")],
    },
    "d3_effects": False,
    "repo": ("clean-s1c", "cross"),
}


def delta_rpm_grid(top, bottom, step):
    """A coast-down logged by a monitoring system that stores a vector
    every `step` [Hz] of speed change (a "delta rpm" trigger): speeds from
    `bottom` to `top` [Hz] in equal steps (listed rising); the trigger's
    phase shifted by a fraction of a step per seed in the digit cases
    (bounded, unlike uniform_grid's shift)."""
    n = int(round((top - bottom) / step)) + 1
    def speeds(shifted, seed):
        frac = (0.37 * (seed - 1)) % 1.0 if shifted else 0.0
        v = bottom + step * (np.arange(n) + frac)
        return np.round(v[v <= top + 1e-9], 4)
    return speeds


# unseen-seven (session 46) is tests/data/ross-unseen-7/unseen-seven.toml: a
# small steam turbine-generator set (about 8 MW, 3000 rpm) on three plain
# cylindrical journals (short oil films, L/D 0.5, heavily loaded: strongly
# cross-coupled, stiffness rising steeply at low speed); the turbine rotor
# (three wheels) on B1 and B2, rigidly coupled to a single-bearing
# generator (a 5 t slotted body) whose far end runs in B3, an exciter
# overhung beyond it. Pedestals heavy (0.8-1.5 t), vertical resonances
# above the run (71-80 Hz), horizontal ones inside it (47, 39, 36 Hz); the
# rotor's criticals at 17 and 24-30 Hz (ROSS run_modal, log dec 0.06-0.3;
# none below zero up to 67 Hz at 10, 30 and 50 Hz: no whip in the run).
SUB_BASE_SEVEN = {"bearing": "B1", "m_y": 400.0, "m_z": 400.0, "k_y": 3.0e8, "k_z": 1.5e8,
                  "c_y": 2.0e4, "c_z": 1.2e4}
# a spring-mounted table-top foundation deck under all three pedestals
DECK_SEVEN = {"name": "deck", "bearings": ["B1", "B2", "B3"], "m_y": 8000.0, "m_z": 8000.0,
              "k_y": 2.5e9, "k_z": 6.0e8, "c_y": 1.5e5, "c_z": 6.0e4}
# table-thermal: the effective film temperature falls as the shear heating
# (about mu Omega^2) falls during the coast-down: Delta T = Delta T_top
# (f / f_top)^2 above the controlled inlet, mu = mu_top exp(beta (Delta
# T_top - Delta T)), beta Delta T_top = ln 1.3 (about 6 C on an ISO VG 32
# oil): +30 % at standstill, +29 % at 5 Hz, 0 at the top speed (50 Hz),
# on every bearing (one oil system); bearings.csv and the machine file
# are at the design viscosity (the top speed's)
THERMAL_SEVEN = {"bearings": ["B1", "B2", "B3"], "top_hz": 50.0, "ratio": 1.3}
# sweep: a trip with the condenser vacuum broken (50 Hz to rest in about
# 100 s: 0.5 Hz/s, an estimate for a small set) and a monitoring system
# whose 1X vector is the average over 32 revolutions (the tracking
# filter's block): each phasor the mean of the steady-state phasors over
# the speeds those revolutions span (the quasi-static part of the sweep)
SWEEP_SEVEN = {"rate_hz_per_s": 0.5, "revolutions": 32, "points": 9}
MACHINES["unseen-seven"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-7"),
    "file": "unseen-seven.toml",
    # a coast-down after a trip from 3000 rpm, a vector stored every 45 rpm
    # (0.75 Hz, a common delta-rpm setting of transient logging), 50 Hz
    # down to 5 Hz (below it the turning-gear approach, not logged): 61
    # speeds, through the rotor's criticals (17, 24-30 Hz) and the three
    # horizontal pedestal resonances
    "grid": delta_rpm_grid(50.0, 5.0, 0.75),
    # proximity probes (API 670 systems): 0.4 % of |phasor| (the 1X
    # filter's scatter) plus an absolute floor of 0.05 um (electrical noise
    # through the tracking filter); casing velocity pick-ups: 1 % of
    # |phasor| plus a velocity floor of 5 um/s (the pick-up's noise in the
    # filter's band, 1.6e-7 m at 5 Hz: the pick-ups read near it below
    # 8 Hz)
    "noise": {"rel": {"rel": 0.004, "floor": 0.0, "abs": 5e-8},
              "ped": {"rel": 0.01, "floor": 0.0, "vel": 5e-6}},
    "noisy": "t1",
    "digits": ("d3", "dmix", "d12"),
    "mixed_digits": {"B1": 3, "B2": 2, "B3": 4},
    "rng": 46_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_SEVEN)],
        "table-film": [("worn_film", "B3", 1.0 / 0.85)],
        "cross": [("cross", "B2", 0.2)],
        "runout": [("runout", "B1")],
        "delay": [("delay", "B2", 150e-6)],
        "flips": [("flips", ["B2", "B3"])],
        "outlier": [("outlier", "B3")],
        "base": [("frame", DECK_SEVEN)],
        "base-runout": [("frame", DECK_SEVEN), ("runout", "B3")],
        "cross-delay": [("cross", "B3", 0.2), ("delay", "B1", 150e-6)],
        # departures no library effect names
        "table-thermal": [("thermal", THERMAL_SEVEN)],
        # B3's casing pick-ups wired to the generator's own monitoring rack,
        # whose anti-alias and integrating filters read 200 us later than
        # the probes' (3.6 deg at 50 Hz)
        "ped-delay": [("ped_delay", "B3", 200e-6)],
        "sweep": [("sweep", SWEEP_SEVEN)],
    },
    "d3_effects": False,
    "repo": ("clean-t1c", "ped-delay"),
}


# unseen-eight (session 47) is tests/data/ross-unseen-8/unseen-eight.toml: a
# high-speed centrifugal gas compressor (a between-bearings barrel machine,
# five 40 kg impellers, 15 000 rpm at the top) on two five-pad tilting-pad
# journals (tables: no cross-coupling, k rising and c falling with speed,
# y stiffer than z), light stiff pedestals (70-90 kg, resonances 290-430 Hz,
# above the run) on a common skid; the rotor's first criticals (about
# 184 Hz horizontal, 242 Hz vertical, ROSS's response peaks) inside a fast
# trip run-down from 250 to 100 Hz logged every 0.4 Hz (376 speeds).
SUB_BASE_EIGHT = {"bearing": "B2", "m_y": 150.0, "m_z": 150.0, "k_y": 4.0e8, "k_z": 2.0e8,
                  "c_y": 8.0e3, "c_z": 5.0e3}
# the common skid on its anti-vibration mounts (its own modes 159 Hz y,
# 100 Hz z: inside the run)
SKID_EIGHT = {"name": "skid", "bearings": ["B1", "B2"], "m_y": 1500.0, "m_z": 1500.0,
              "k_y": 1.5e9, "k_z": 6.0e8, "c_y": 1.5e5, "c_z": 9.5e4}
# the trip: gas load and windage bring the rotor from 250 Hz to 100 Hz in
# about 30 s (5 Hz/s, an estimate); a vector stored every 0.4 Hz (24 rpm),
# one every 0.08 s
RATE_EIGHT = 5.0
# probe-axes: both bearings' proximity probes mounted at 45 deg either side
# of the vertical (the usual X-Y pair of API 670) and written as they read,
# the left-hand probe (-45 deg, towards -z) as rel_y and the right-hand one
# (+45 deg) as rel_z, not resolved to y and z: the rel vector rotated by
# 45 deg; the casing pick-ups at 0 and 90 deg as formats.md wants
PROBE_AXES_EIGHT = {"bearings": ["B1", "B2"], "angle_deg": 45.0}
# kp-lag: the monitoring system's speed is the keyphasor's pulse rate
# through a first-order filter of 0.05 s (its own speed filter), which
# lags a ramp by 0.05 s, so in the 5 Hz/s run-down the speed column reads
# 5 * 0.05 = 0.25 Hz high (0.6 of the 0.4 Hz logging step); bearings.csv
# written at the stamped speeds (the table interpolated there)
KP_LAG_EIGHT = {"rate_hz_per_s": RATE_EIGHT, "lag_s": 0.05}
# corr-noise: the tracking filter's time constant (0.36 s) longer than the
# 0.08 s between stored vectors: the noise of successive vectors of a
# channel is correlated, rho = exp(-0.08 / 0.36) = 0.80 (an AR(1) along
# the run, the same marginal sigma the *_sd columns give)
CORR_NOISE_EIGHT = {"rate_hz_per_s": RATE_EIGHT, "step_hz": 0.4, "filter_tau_s": 0.36}
MACHINES["unseen-eight"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-8"),
    "file": "unseen-eight.toml",
    "grid": delta_rpm_grid(250.0, 100.0, 0.4),
    # proximity probes: 0.5 % of |phasor| + 0.02 um (electrical noise
    # through the tracking filter); casing accelerometers: 1 % of |phasor|
    # + an acceleration floor of 5 mm/s^2 (1.3e-8 m at 100 Hz, 2e-9 m at
    # 250 Hz: B2's vertical pick-up reads near it at the bottom of the run)
    "noise": {"rel": {"rel": 0.005, "floor": 0.0, "abs": 2e-8},
              "ped": {"rel": 0.01, "floor": 0.0, "acc": 5e-3}},
    "noisy": "g1",
    "digits": ("d3", "dmix", "d12"),
    "mixed_digits": {"B1": 3, "B2": 2},
    "rng": 47_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_EIGHT)],
        "table-scale": [("table_scale", "B1", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B2", 0.2)],
        "runout": [("runout", "B1")],
        # 40 us on B2's probes (3.6 deg at 250 Hz)
        "delay": [("delay", "B2", 40e-6)],
        "flips": [("flips", ["B1", "B2"])],
        "outlier": [("outlier", "B1")],
        "base": [("frame", SKID_EIGHT)],
        "base-runout": [("frame", SKID_EIGHT), ("runout", "B2")],
        "cross-delay": [("cross", "B1", 0.2), ("delay", "B2", 40e-6)],
        # departures no machine had (no library name)
        "probe-axes": [("probe_axes", PROBE_AXES_EIGHT)],
        "kp-lag": [("speed_lag", KP_LAG_EIGHT)],
        "corr-noise": [("corr_noise", CORR_NOISE_EIGHT)],
    },
    "d3_effects": False,
    # bearings.csv at the tables' own rows (90, 175, 260 Hz), not at the
    # 376 speeds: the same coefficients, the stored runs a third the size
    "table_rows": True,
    "repo": ("clean-g1c", "cross"),
}


# unseen-nine (session 48) is tests/data/ross-unseen-9/unseen-nine.toml: a
# large turbocharger (of a gas engine of about 2 MW, 30 000 rpm at the
# top): a short stiff rotor with both wheels overhung outboard of two
# floating-ring journals (a table: stiffness rising 3.4-fold, damping
# falling 2.7-fold with speed, strongly cross-coupled, k_yz = -k_zy about
# 0.35 k_yy), strong gyroscopic coupling (the wheels' polar inertia); the
# pedestals the two ends of the bearing housing: B1 (compressor end) light
# and stiff (resonances 650-840 Hz, above the run), B2 (turbine end, hot,
# on a fabricated support) heavier and softer (275 Hz horizontal, 367 Hz
# vertical, inside the run); a coast-down after the engine stops, 500 Hz
# to 100 Hz.
SUB_BASE_NINE = {"bearing": "B2", "m_y": 40.0, "m_z": 40.0, "k_y": 2.5e8, "k_z": 1.5e8,
                 "c_y": 6000.0, "c_z": 4000.0}
# the turbocharger's mounting foot on the engine: both housing ends on one
# cast bracket (its own modes 410 Hz y, 252 Hz z: inside the run)
FOOT_NINE = {"name": "foot", "bearings": ["B1", "B2"], "m_y": 120.0, "m_z": 120.0,
             "k_y": 8.0e8, "k_z": 3.0e8, "c_y": 2.0e4, "c_z": 1.2e4}
# the coast-down's clock: the rotor decelerates by its bearings' drag (a
# torque about proportional to the speed), so the speed falls exponentially
# in time, 500 Hz to 100 Hz in 90 s, and a vector logged every second
# makes the grid geometric; the turbine end cools with the exhaust gas
# gone, a first-order lag of 60 s (scripts/ross_unseen.py, cooling_fraction)
COOLING_NINE = {"top_hz": 500.0, "bottom_hz": 100.0, "duration_s": 90.0, "tau_s": 60.0}
# ped-drift: the turbine-end housing and its support cool by about 130 K
# during the coast-down and their stiffness (E of the cast steel about
# +3 % per 100 K of cooling, the bolted joints' preload) rises by 4 % from
# the top of the run to its bottom, k(f) = k_file (1 + 0.04 (x(f) - 1/2)),
# x the cooling fraction (0 at the top, 1 at the bottom): the machine
# file's k is the value half way through the cooling
PED_DRIFT_NINE = dict(COOLING_NINE, bearing="B2", span=0.04)
# ped-drift-up: the same machine run up right after the coast-down (a
# restart at idle: the exhaust gas still cooler than the turbine end, which
# goes on cooling), by the same exponential clock reversed, 100 Hz to
# 500 Hz in 90 s; B2's stiffness again rises 4 % over the run, following
# time, so now rising with speed (ross_unseen.drift_factor, run_up): the
# second run in which time runs the other way in speed (`plinth compare`)
PED_DRIFT_UP_NINE = dict(PED_DRIFT_NINE, run_up=True)
# probe-gain: B1's vertical proximity probe calibrated on a target of
# another steel than the compressor-end journal's (API 670 asks for the
# shaft's own): on this shaft it reads 5 % low (a sensitivity error of one
# channel, not a unit mistake)
PROBE_GAIN_NINE = {"bearing": "B1", "channel": "rel_y", "gain": 0.95}
# runout-drift: the electrical runout of B2's probes (the turbine-end
# journal's magnetic and electrical properties vary round it and with its
# temperature) changes as the journal cools: the runout vector of
# probe_runout at the top of the run, growing 1.8-fold and turning 40 deg
# by the bottom, with the cooling fraction
RUNOUT_DRIFT_NINE = dict(COOLING_NINE, bearing="B2", growth=0.8, turn_deg=40.0)
MACHINES["unseen-nine"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-9"),
    "file": "unseen-nine.toml",
    # a vector a second in an exponential coast-down: 90 speeds from
    # 500 Hz down to 100 Hz in a constant ratio (1.8 % per step)
    "grid": coast_down_grid(500.0, 100.0, 90),
    # proximity probes: 0.5 % of |phasor| + 0.01 um; casing accelerometers
    # 1 % of |phasor| + an acceleration floor of 2 mm/s^2 (5e-9 m at
    # 100 Hz: B1's pick-ups, on the stiff end, read 2-4e-8 m there)
    "noise": {"rel": {"rel": 0.005, "floor": 0.0, "abs": 1e-8},
              "ped": {"rel": 0.01, "floor": 0.0, "acc": 2e-3}},
    "noisy": "r1",
    "digits": ("d3", "dmix", "d12"),
    "mixed_digits": {"B1": 3, "B2": 2},
    "rng": 48_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_NINE)],
        "table-scale": [("table_scale", "B1", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B2", 0.2)],
        "runout": [("runout", "B1")],
        # 30 us on B2's probes (5.4 deg at 500 Hz)
        "delay": [("delay", "B2", 30e-6)],
        "flips": [("flips", ["B1", "B2"])],
        "outlier": [("outlier", "B2")],
        "base": [("frame", FOOT_NINE)],
        "base-runout": [("frame", FOOT_NINE), ("runout", "B2")],
        "cross-delay": [("cross", "B1", 0.2), ("delay", "B2", 30e-6)],
        # departures no machine had
        "ped-drift": [("ped_drift", PED_DRIFT_NINE)],
        "probe-gain": [("probe_gain", PROBE_GAIN_NINE)],
        "runout-drift": [("runout_drift", RUNOUT_DRIFT_NINE)],
        # appended last: the other cases' random numbers stay as they were
        "ped-drift-up": [("ped_drift", PED_DRIFT_UP_NINE)],
    },
    "d3_effects": False,
    "table_rows": True,
    "repo": ("clean-r1c", "cross"),
}


# unseen-ten (session 50) is tests/data/ross-unseen-10/unseen-ten.toml: a
# two-pole induction motor (about 400 kW, 6000 rpm at the top of its
# variable-frequency drive), the first SYMMETRIC machine: a 150 kg rotor core
# between two deep-groove ball bearings (isotropic tables, no cross-coupling,
# almost no damping, stiffness falling 10 % with speed), a coupling hub and
# the cooling fan overhung; the pedestals are the two end shields, nearly
# isotropic (k_z 6-7 % below k_y), lightly damped (3 %), their resonances
# (76-87 Hz) and the rotor's first critical inside the run. The orbits are
# near circles (forward whirl), so y and z readings are almost the same
# information turned by 90 deg: what is separable on the nine anisotropic
# machines (a cross-coupled stiffness from a damping, one direction's
# sensitivity from the other's) may not be here.
# The non-drive-end foot on a cracked grout pad / soft shim stack: its own
# sub-base under B2's end shield
SUB_BASE_TEN = {"bearing": "B2", "m_y": 80.0, "m_z": 80.0, "k_y": 4.0e7, "k_z": 2.5e7,
                "c_y": 3000.0, "c_z": 2000.0}
# the motor on a fabricated steel baseplate (its own modes 97 Hz y, 62 Hz z)
BASEPLATE_TEN = {"name": "baseplate", "bearings": ["B1", "B2"], "m_y": 400.0, "m_z": 400.0,
                 "k_y": 1.5e8, "k_z": 6.0e7, "c_y": 8000.0, "c_z": 4000.0}
# the drive's ramp: 100 Hz to 10 Hz in 45 s (2 Hz/s); the speed the
# monitoring system stamps is its keyphasor rate through a 0.1 s filter,
# 0.2 Hz high (0.1 of the 2 Hz logging step)
SPEED_LAG_TEN = {"rate_hz_per_s": 2.0, "lag_s": 0.1}
# B2's horizontal probe calibrated on another target steel: 5 % low
PROBE_GAIN_TEN = {"bearing": "B2", "channel": "rel_z", "gain": 0.95}
MACHINES["unseen-ten"] = {
    "data": os.path.join(ROOT, "tests", "data", "ross-unseen-10"),
    "file": "unseen-ten.toml",
    # the drive ramps the speed down from 100 Hz to 10 Hz; a vector logged
    # at every 2 Hz of speed (46 speeds; the digit cases' trigger phase
    # shifted by the seed, bounded: uniform_grid's shift grows with it)
    "grid": delta_rpm_grid(100.0, 10.0, 2.0),
    # proximity probes: 0.5 % of |phasor| + 0.03 um (electrical noise and
    # the drive's interference through the tracking filter); casing
    # velocity pick-ups: 1 % of |phasor| + 2 um/s (3.2e-8 m at 10 Hz)
    "noise": {"rel": {"rel": 0.005, "floor": 0.0, "abs": 3e-8},
              "ped": {"rel": 0.01, "floor": 0.0, "vel": 2e-6}},
    "noisy": "v1",
    "digits": ("d3", "d2"),
    "rng": 50_000,
    "effects": {
        "sub-base": [("sub_base", SUB_BASE_TEN)],
        "table-scale": [("table_scale", "B1", 1.0 / 1.25, 1.0)],
        "cross": [("cross", "B1", 0.2)],
        "runout": [("runout", "B2")],
        # 100 us on B1's probes (3.6 deg at 100 Hz)
        "delay": [("delay", "B1", 100e-6)],
        "flips": [("flips", ["B1", "B2"])],
        "outlier": [("outlier", "B1")],
        "base": [("frame", BASEPLATE_TEN)],
        "probe-gain": [("probe_gain", PROBE_GAIN_TEN)],
        "speed-lag": [("speed_lag", SPEED_LAG_TEN)],
        "base-runout": [("frame", BASEPLATE_TEN), ("runout", "B1")],
        "cross-delay": [("cross", "B2", 0.2), ("delay", "B1", 100e-6)],
    },
    "d3_effects": False,
    "table_rows": True,
    # the stored runs are of seeds 9500-9699 (tests/data/ross-unseen-10/
    # CASE-SEED, docs/unseen-ten.md), not seed 1
    "repo": (),
}
