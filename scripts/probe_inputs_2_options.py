"""Probe 2 cases for machine files (simulate, accuracy, signals, diagnose,
paper, demo) and for command-line options (--speeds, signals, accuracy,
demo/paper, stream).
"""
import os
import re

from probe_inputs_common import *  # noqa: F401,F403


# --- machine files
MACHINE_BAD = [
    ("negative length", lambda: machine_edit("length = 1.0", "length = -1.0")),
    ("zero diameter", lambda: machine_edit("outer_diameter = 0.1\nelements = 10", "outer_diameter = 0.0\nelements = 10")),
    ("young nan", lambda: machine_edit("young_modulus = 2.11e11", "young_modulus = nan")),
    ("disk density inf", lambda: machine_edit("density = 7810.0\nunbalance = 1.0e-4 ", "density = inf\nunbalance = 1.0e-4 ")),
    ("bearing outside the shaft", lambda: machine_edit("position = 1.1", "position = 5.0")),
    ("bearing at negative position", lambda: machine_edit("position = 0.1\noil_film", "position = -0.3\noil_film")),
    ("no bearing", lambda: MACHINE_TEXT.split("[[bearings]]")[0]),
    ("one bearing", lambda: "[[bearings]]".join(MACHINE_TEXT.split("[[bearings]]")[:2])),
    ("disk outside the shaft", lambda: machine_edit("position = 0.8 ", "position = 7.8 ")),
    ("elements 0", lambda: machine_edit("elements = 10", "elements = 0")),
    ("elements -1", lambda: machine_edit("elements = 10", "elements = -1")),
    ("elements 1e9", lambda: machine_edit("elements = 10", "elements = 1000000000")),
    ("disk bore larger than disk", lambda: machine_edit("inner_diameter = 0.1", "inner_diameter = 0.7")),
    ("density 0", lambda: machine_edit("density = 7810.0 }", "density = 0.0 }")),
    ("pedestal mass negative", lambda: machine_edit("m = 80.0", "m = -80.0")),
    ("pedestal stiffness negative", lambda: machine_edit("k_y = 10.0e6", "k_y = -10.0e6")),
    ("two bearings one name", lambda: machine_edit('name = "right"', 'name = "left"')),
    ("two bearings one position", lambda: machine_edit("position = 1.1", "position = 0.1")),
    ("unbalance nan", lambda: machine_edit("unbalance = 1.0e-4 ", "unbalance = nan ")),
    ("unbalance 1e300", lambda: machine_edit("unbalance = 1.0e-4 ", "unbalance = 1.0e300 ")),
    ("clearance negative", lambda: machine_edit("clearance = 40.0e-6", "clearance = -40.0e-6")),
    ("viscosity 0", lambda: machine_edit("viscosity = 0.0069", "viscosity = 0.0")),
    ("load unknown", lambda: machine_edit('load = "weight"', 'load = "heavy"')),
    ("poisson 0.5", lambda: machine_edit("poisson_ratio = 0.3", "poisson_ratio = 0.5")),
    ("poisson 2", lambda: machine_edit("poisson_ratio = 0.3", "poisson_ratio = 2.0")),
    ("bearing name path", lambda: machine_edit('name = "left"', 'name = "../left"')),
    ("bearing name empty", lambda: machine_edit('name = "left"', 'name = ""')),
    ("unknown key typo", lambda: machine_edit("length = 1.0", "lenght = 1.0")),
    ("sections empty", lambda: re.sub(r"\[\[shaft\.sections\]\].*?(?=\[\[disks\]\])", "", MACHINE_TEXT, flags=re.S)),
    ("clearance larger than radius", lambda: machine_edit("clearance = 40.0e-6", "clearance = 0.2")),
    ("bearing length 0", lambda: machine_edit("length = 0.0254", "length = 0.0")),
    ("unbalance angle 1e20", lambda: machine_edit("unbalance_angle = 60.0", "unbalance_angle = 1e20")),
    ("disk width negative", lambda: machine_edit("width = 0.08", "width = -0.08")),
    ("shaft 1 km", lambda: machine_edit("length = 1.0", "length = 1000.0")),
]


@builder
def machine_bad(d):
    name, f = rng.choice(MACHINE_BAD)
    c = machine_case(d, f())
    if name in ("unbalance angle 1e20", "shaft 1 km"):
        c["expect"] = "any"
    c["what"] = f"machine: {name}"
    return c


@builder
def machine_bad_2(d):
    return machine_bad(d)


@builder
def machine_bad_3(d):
    return machine_bad(d)


# --- options
SPEEDS_BAD = ["60:5:1", "5:60:0", "5:60:-1", "0:1e9:1", "5,5,5", "5,,6", "-5:10:1", "0:10:1", "nan:10:1",
              "5:60:1e-300", "5:5:1", "1e308:1e308:1", " 5 : 60 : 5 ", "5:60", "5:60:1:2", "5;6;7",
              "5:60:1e-9", "inf:5:1", "5:60:inf", "1e-300:1e-299:1e-301", "6,5,4", "5,nan,6", "0x10:60:5"]


@builder
def speeds_option(d):
    s = rng.choice(SPEEDS_BAD)
    which = rng.choice(["simulate", "accuracy", "paper"])
    if which == "simulate":
        argv = ["simulate", MACHINE, "--speeds", s, "--out", d + "/out"]
    elif which == "accuracy":
        argv = ["accuracy", MACHINE, "--draws", "2", "--speeds", s]
    else:
        argv = ["paper", "--speeds", s]
    ok = s in (" 5 : 60 : 5 ", "6,5,4")
    return {"argv": argv, "out": d + "/out", "expect": "any" if ok else "error", "command": which,
            "what": f"--speeds {s!r}"}


@builder
def signals_option(d):
    o = rng.choice([["--rundown", "60:50:0"], ["--rundown", "60:60:5"], ["--rundown", "50:60:5"],
                    ["--rundown", "60:-5:5"], ["--rundown", "1e9:5:5"], ["--rundown", "60:50:1e-9"],
                    ["--rundown", "60:50:-5"], ["--rundown", "nan:5:5"], ["--rundown", "60:50"],
                    ["--rate", "1e-3"], ["--rate", "10"], ["--grid-step", "1e3"], ["--adc-range", "1e-300"],
                    ["--probe-v-per-mm", "1e300"], ["--seismic-sensitivity", "1e-300"], ["--seismic-sensitivity", "1e-9"], ["--adc-bits", "1"],
                    ["--effect", "nosuch"], ["--effect", "probe_runout:nobearing=1"],
                    ["--effect", "sensor_delay=1e300"]])
    argv = ["signals", MACHINE, "--out", d + "/out"] + (["--rundown", "60:50:5"] if o[0] != "--rundown" else []) + o
    exp = "any" if o in (["--rundown", "50:60:5"], ["--rate", "10"]) else "error"
    if o in (["--adc-range", "1e-300"], ["--probe-v-per-mm", "1e300"], ["--seismic-sensitivity", "1e-300"],
             ["--seismic-sensitivity", "1e-9"]):
        exp = "warn"  # every sample clipped: said, naming --adc-range
    if o == ["--rate", "10"] or o == ["--rate", "1e-3"]:
        exp = "warn"
    return {"argv": argv, "out": d + "/out", "expect": exp, "command": "signals", "what": "signals " + " ".join(o)}


@builder
def accuracy_option(d):
    o = rng.choice([["--draws", "0"], ["--draws", "1"], ["--digits", "0"], ["--digits", "100"], ["--noise", "0"],
                    ["--noise", "-1"], ["--draws", "18446744073709551615"], ["--noise", "nan"],
                    ["--digits", "1"], ["--seed", "-1"]])
    exp = "any" if o in (["--digits", "1"], ["--draws", "1"]) else "error"
    if o == ["--draws", "1"]:
        exp = "warn"
    return {"argv": ["accuracy", MACHINE, "--speeds", "5:60:5"] + (["--draws", "2"] if o[0] != "--draws" else []) + o,
            "out": d + "/out", "expect": exp, "command": "accuracy", "what": "accuracy " + " ".join(o)}


@builder
def demo_paper_option(d):
    which = rng.choice(["demo", "paper"])
    if which == "demo":
        o = rng.choice([["--rundown", "60:5:0"], ["--averaging", "0"], ["--averaging", "4294967295"],
                        ["--rundown", "60:59.9:5", "--averaging", "1000"], ["--seismic", "laser"],
                        ["--elf", "/nonexistent"]])
        argv = ["demo", "--out", d + "/out"] + (["--rundown", "60:50:5"] if "--rundown" not in o else []) + o
    else:
        o = rng.choice([["--heavy-damping-ratio", "-1"], ["--heavy-damping-ratio", "nan"],
                        ["--heavy-damping-ratio", "1e9"], ["--plots", d + "/existing.txt"]])
        open(d + "/existing.txt", "w").write("my notes\n")
        argv = ["paper", "--speeds", "5:60:5"] + o
    return {"argv": argv, "out": d + "/out", "expect": "error", "command": which, "what": f"{which} " + " ".join(o)}


def stream_config(d, run, mutate=None):
    s = f'bearings = "{run}/bearings.csv"\n'
    for b, bearing in enumerate(["left", "right"]):
        for q, quantity in enumerate(["rel_y", "rel_z", "ped_y", "ped_z"]):
            s += (f'\n[[channels]]\nadc = {4 * b + q}\nbearing = "{bearing}"\nquantity = "{quantity}"\n'
                  'sensor = "proximity"\nsensitivity = 7870.0\n')
    if mutate:
        s = mutate(s)
    p = os.path.join(d, "stream.toml")
    open(p, "w").write(s)
    return p


@builder
def stream_cases(d):
    r = copy_run(d, "tables")
    style = rng.choice(["window-huge", "port-regular-file", "port-dev-null", "replay-missing", "replay-file",
                        "config-adc-99", "config-dup-adc", "config-no-bearings", "out-is-file", "baud-0",
                        "offline-no-log"])
    cfg = stream_config(d, r)
    exp = "error"
    base = ["stream", "--config", cfg, "--out", d + "/out", "--handshake-timeout", "2", "--reconnect-timeout", "2"]
    if style == "window-huge":
        argv = base + ["--port", "/dev/null", "--window", rng.choice(["1000000000000", "4294967296"])]
    elif style == "port-regular-file":
        open(d + "/notes.csv", "w").write("speed,amp\n1,2\n")
        argv = base + ["--port", d + "/notes.csv", "--duration", "2"]
    elif style == "port-dev-null":
        argv = base + ["--port", "/dev/null", "--duration", "2"]
    elif style == "replay-missing":
        argv = base + ["--port", "/dev/null", "--replay", d + "/nosuch"]
    elif style == "replay-file":
        argv = base + ["--port", "/dev/null", "--replay", r + "/measurements.csv"]
    elif style == "config-adc-99":
        cfg = stream_config(d, r, lambda s: s.replace("adc = 7", "adc = 99"))
        argv = base + ["--port", "/dev/null", "--duration", "2"]
    elif style == "config-dup-adc":
        cfg = stream_config(d, r, lambda s: s.replace("adc = 7", "adc = 6"))
        argv = base + ["--port", "/dev/null", "--duration", "2"]
    elif style == "config-no-bearings":
        cfg = stream_config(d, r, lambda s: s.replace(f'{r}/bearings.csv', f'{r}/nosuch.csv'))
        argv = base + ["--port", "/dev/null", "--duration", "2"]
    elif style == "out-is-file":
        open(d + "/out", "w").write("precious\n")
        argv = base + ["--port", "/dev/null", "--duration", "2"]
    elif style == "baud-0":
        argv = base + ["--port", "/dev/null", "--baud", "0", "--duration", "2"]
    else:
        os.mkdir(d + "/out")
        open(d + "/out/notes.txt", "w").write("mine\n")
        argv = ["stream", "--offline", "--config", cfg, "--out", d + "/out"]
    return {"argv": argv, "out": d + "/out", "expect": exp, "command": "stream", "what": f"stream {style}"}
