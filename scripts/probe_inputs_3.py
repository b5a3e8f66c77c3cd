"""The cases of scripts/probe-inputs-3.sh (read its header).

A third bad-input probe with cases neither scripts/probe-inputs.sh nor
scripts/probe-inputs-2.sh makes: field-data oddities (a keyphasor with
double pulses, a WAV whose rate is not the one it was sampled at, a channel
listed twice, a second coast-down appended), one non-finite spelling in one
cell of every table, names with a byte-order mark, CRLF and trailing
spaces that differ between files, exponents at the ends of the doubles, a
run directory that is a symbolic-link loop or an alias of --out, two
--force writers at once and SIGINT in the middle of a write, over every
command. Builders, baselines and the runner are the ones of probe 2
(probe_inputs_common.py, probe_inputs_runner.py).
"""
import os
import shutil
import struct

from probe_inputs_common import *  # noqa: F401,F403
from probe_inputs_runner import main

P3 = []
# A run with a measured base (base.csv): the skid machine's.
must(["simulate", SKID, "--speeds", "5:60:1", "--out", W + "/skid-run"])


def builder3(f):
    P3.append(f)
    return f


RUN_COMMANDS = ["identify", "diagnose", "plot", "report"]


# ------------------------------------------------------ field-data oddities
@builder3
def keyphasor_double_pulses(d):
    """Each keyphasor notch seen twice (a keyway's two edges, a second mark):
    the speed from the pulses is doubled. Must not pass silently."""
    c, i, rec = extract_case(d, "warn", csv=True)
    rows = csv_rows(rec)
    kp = rows[0].index("c8")
    low = [n for n in range(1, len(rows)) if float(rows[n][kp]) < -5.0]
    starts = [n for n in low if float(rows[n - 1][kp]) >= -5.0]
    gap = rng.choice(["quarter", "third", "half"])
    for s in starts:
        nxt = next((t for t in starts if t > s), None)
        if nxt is None:
            break
        at = s + (nxt - s) // {"quarter": 4, "third": 3, "half": 2}[gap]
        for k in range(3):
            if at + k < len(rows):
                rows[at + k][kp] = "-9.0"
    write_rows(rec, rows)
    c["what"] = f"keyphasor with a second pulse at a {gap} revolution"
    return c


@builder3
def wav_rate_disagrees(d):
    """The WAV header's sample rate is not the one the samples were taken
    at (a recorder set to 2x, a resampled file with the old header)."""
    # Not detectable from the samples (a machine at twice the speed looks
    # the same): what can be asked is a warning when speeds leave the
    # bearing table's range.
    c, i, rec = extract_case(d, "warn", csv=False)
    data = bytearray(open(rec, "rb").read())
    fmt = data.index(b"fmt ") + 8
    rate = struct.unpack("<I", data[fmt + 4:fmt + 8])[0]
    factor = rng.choice([2.0, 0.5, 4.0, 0.25])
    new = int(rate * factor)
    ch = struct.unpack("<H", data[fmt + 2:fmt + 4])[0]
    bits = struct.unpack("<H", data[fmt + 14:fmt + 16])[0]
    data[fmt + 4:fmt + 8] = struct.pack("<I", new)
    data[fmt + 8:fmt + 12] = struct.pack("<I", new * ch * bits // 8)
    open(rec, "wb").write(data)
    # Every speed scales by the factor: outside bearings.csv's range.
    c["what"] = f"WAV header rate x{factor} of the true one"
    return c


@builder3
def channel_listed_twice(d):
    """channels.toml lists one input twice: copied block, or two inputs for
    one bearing/quantity/angle, or one input as two quantities."""
    c, i, rec = extract_case(d, "error", csv=rng.random() < 0.5)
    t = open(i + "/channels.toml").read()
    blocks = t.split("[[channel]]")
    style = rng.choice(["same-block", "same-place", "rel-and-ped"])
    if style == "same-block":
        t = t + "\n[[channel]]" + blocks[3]
    elif style == "same-place":
        # index 6 measures what index 7 measures (ped 90 at right)
        t = t.replace("index = 6\nbearing = \"right\"\nquantity = \"ped\"\nangle_deg = 0.0",
                      "index = 6\nbearing = \"right\"\nquantity = \"ped\"\nangle_deg = 90.0")
    else:
        extra = blocks[1].replace("quantity = \"rel\"", "quantity = \"ped\"").replace("angle = \"45L\"", "angle_deg = 45.0")
        t = t + "\n[[channel]]" + extra
    open(i + "/channels.toml", "w").write(t)
    c["what"] = f"channels.toml names an input twice: {style}"
    return c


@builder3
def second_coast_down(d):
    """A run-down, a restart and a second run-down in one recording (the
    speed descends, jumps up, descends again): either averaged per speed
    (the same run again) or refused, never garbage."""
    c, i, rec = extract_case(d, "any", csv=True)
    rows = csv_rows(rec)
    body = rows[1:]
    step = float(body[1][0]) - float(body[0][0])
    t_end = float(body[-1][0]) + step
    style = rng.choice(["again", "run-up-reversed"])
    again = body if style == "again" else body[::-1]
    extra = [[f"{t_end + k * step:.9f}"] + x[1:] for k, x in enumerate(again)]
    write_rows(rec, [rows[0]] + body + extra)
    c["what"] = f"recording: a run-down then {style}"
    return c


# ------------------------------------------------------ numbers and names
NAN_SPELLINGS = ["NaN", "nan", "-nan", "+NaN", "inf", "-inf", "+inf", "Infinity", "-Infinity", "1.#INF",
                 "1.#IND", "#NUM!", "#DIV/0!", "∞", "nan(0x1)"]


@builder3
def non_finite_cell(d):
    """One cell of one numeric column of one table holds a non-finite
    spelling: every table the commands read. The error names its line."""
    table = rng.choice(["measurements", "bearings", "base", "vector-table", "field-bearings", "recording"])
    value = rng.choice(NAN_SPELLINGS)
    if table in ("measurements", "bearings", "base"):
        c, r = identify_case(d, "error", rng.choice(RUN_COMMANDS))
        path = r + f"/{table}.csv"
        if table == "base":  # the skid run's measured base motion
            shutil.rmtree(r)
            shutil.copytree(W + "/skid-run", r)
    elif table in ("vector-table", "field-bearings"):
        c, i = import_case(d, "error")
        path = i + ("/vector-table.csv" if table == "vector-table" else "/bearings.csv")
        layout = open(i + "/layout.toml").read()
    else:
        c, i, path = extract_case(d, "error", csv=True)
    rows = csv_rows(path)
    numeric = [j for j in range(len(rows[0])) if j < len(rows[1]) and _is_number(rows[1][j])
               and (table != "vector-table" or f'"{rows[0][j]}"' in layout)]  # columns the layout reads
    j = rng.choice(numeric)
    n = rng.randrange(1, len(rows))
    rows[n][j] = value
    write_rows(path, rows)
    if table == "recording" and value.lower().lstrip("+-") in ("nan", "inf"):
        c["expect"] = "any"  # probe 2's nan-sample: a sample gap is legitimate to skip or refuse
    c["names_line"] = True
    c["what"] = f"{table}.csv line {n + 1} column {rows[0][j]!r} = {value!r}"
    return c


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


@builder3
def names_bom_crlf_spaces(d):
    """measurements.csv and bearings.csv written by two tools: one with a
    byte-order mark and CRLF, the names padded with spaces or a tab in one
    file only. The same run (neutral) or a clear error."""
    cmd = rng.choice(["identify", "identify", "plot", "report", "diagnose"])
    c, r = identify_case(d, "neutral", cmd)
    pad = rng.choice(["  ", " \t", "\t"])
    which = rng.choice(["measurements.csv", "bearings.csv"])
    rows = csv_rows(r + "/" + which)
    for x in rows[1:]:
        x[1] = x[1] + pad
    text = "\ufeff" + "\r\n".join(",".join(x) for x in rows) + "\r\n"
    open(r + "/" + which, "w", encoding="utf-8", newline="").write(text)
    c["what"] = f"{which}: BOM, CRLF, names + {pad!r}"
    return c


EXPONENTS = [("1E-3", "neutral"), ("1e-320", "any"), ("4.9e-324", "any"), ("1e+308", "error"),
             ("1.7976931348623157e308", "error"), ("0x1p-3", "error"), ("1e-3000", "any"),
             ("1d-3", "error"), ("1e", "error"), (".5e-1", "any"), ("5.e-2", "any")]


@builder3
def exponents(d):
    """One number at the ends of the doubles (subnormal, near the largest,
    hex, Fortran's `d`, a bare `e`) in a table or a machine file."""
    where = rng.choice(["measurements", "bearings", "vector-table", "machine"])
    value, exp = rng.choice(EXPONENTS)
    if where == "machine":
        key = rng.choice(["young_modulus = 2.11e11", "length = 1.0", "unbalance = 1.0e-4 ", "density = 7810.0\n"])
        k, _, rest = key.partition(" = ")
        tail = "\n" if key.endswith("\n") else (" " if key.endswith(" ") else "")
        text = machine_edit(key, f"{k} = {value}{tail}")
        c = machine_case(d, text, "any" if exp != "error" else "error")
        c["what"] = f"machine file {k} = {value}"
        return c
    if where == "vector-table":
        c, i = import_case(d, exp if exp != "neutral" else "any")
        path = i + "/vector-table.csv"
        cols = [j for j, h in enumerate(csv_rows(path)[0]) if "Amp" in h]
    else:
        c, r = identify_case(d, exp if exp != "neutral" else "any", rng.choice(RUN_COMMANDS))
        path = r + f"/{where}.csv"
        cols = list(range(2, len(csv_rows(path)[0])))
    rows = csv_rows(path)
    j = rng.choice(cols)
    n = rng.randrange(1, len(rows))
    rows[n][j] = value
    write_rows(path, rows)
    c["names_line"] = exp == "error"
    c["what"] = f"{where}.csv line {n + 1} {rows[0][j]!r} = {value}"
    return c


# ------------------------------------------------- directories and --out
@builder3
def run_dir_links(d):
    """The run directory is a link loop, a link to itself's parent, or its
    measurements.csv a link to the run directory."""
    cmd = rng.choice(RUN_COMMANDS)
    c, r = identify_case(d, "error", cmd)
    style = rng.choice(["loop", "two-loop", "measurements-to-dir", "dir-link-to-file"])
    if style == "loop":
        shutil.rmtree(r)
        os.symlink(r, r)
    elif style == "two-loop":
        shutil.rmtree(r)
        os.symlink(d + "/run2", r)
        os.symlink(r, d + "/run2")
    elif style == "measurements-to-dir":
        os.remove(r + "/measurements.csv")
        os.symlink(r, r + "/measurements.csv")
    else:
        shutil.rmtree(r)
        open(d + "/file.txt", "w").write("a file\n")
        os.symlink(d + "/file.txt", r)
    c["what"] = f"run directory: {style}"
    return c


@builder3
def out_aliases_input(d):
    """--out names the run directory (or the machine file's directory)
    through another spelling: `run/.`, `run/../run`, a link to it. The
    inputs must survive; writing there needs --force."""
    style = rng.choice(["dot", "dotdot", "link", "machine-dir"])
    if style == "machine-dir":
        os.mkdir(d + "/m")
        shutil.copy(MACHINE, d + "/m/machine.toml")
        open(d + "/m/notes.txt", "w").write("mine\n")
        which = rng.choice(["simulate", "signals"])
        argv = ([which, d + "/m/machine.toml", "--speeds", "5:60:5", "--out", d + "/m/."]
                if which == "simulate" else
                [which, d + "/m/machine.toml", "--rundown", "60:55:5", "--out", d + "/m/."])
        return {"argv": argv, "out": d + "/none", "expect": "error", "command": which,
                "what": f"--out {style}"}
    cmd = rng.choice(["plot", "report", "simulate", "import", "extract"])
    r = copy_run(d)
    alias = {"dot": r + "/.", "dotdot": r + "/../run"}.get(style)
    if style == "link":
        os.symlink(r, d + "/alias")
        alias = d + "/alias"
    if cmd in ("plot", "report"):
        argv = [cmd, r, "--out", alias]
    elif cmd == "simulate":
        argv = ["simulate", MACHINE, "--speeds", "5:60:5", "--out", alias]
    elif cmd == "import":
        i = copy_field(d)
        argv = ["import", i + "/vector-table.csv", "--layout", i + "/layout.toml", "--bearings",
                i + "/bearings.csv", "--out", alias]
    else:
        i = copy_field(d)
        argv = ["extract", i + "/recording.wav", "--channels", i + "/channels.toml", "--bearings",
                i + "/bearings.csv", "--out", alias]
    return {"argv": argv, "out": d + "/none", "expect": "error", "command": cmd, "what": f"--out {style} of a run"}


@builder3
def two_force_writers(d):
    """Two commands with --force onto one existing run at once (a user
    re-running a script in a second terminal): one wins, the other names
    the --out, and the user's own file in it survives."""
    out = d + "/out"
    p = run(["simulate", MACHINE, "--speeds", "5:60:5", "--out", out])
    if p.returncode != 0:
        return {"argv": ["simulate"], "out": d + "/none", "expect": "any", "command": "simulate",
                "what": "(setup failed)"}
    open(out + "/my-notes.txt", "w").write("mine\n")
    r = copy_run(d)
    writers = [["simulate", MACHINE, "--speeds", "5:60:2", "--out", out, "--force"],
               ["plot", r, "--out", out, "--force"],
               ["report", r, "--out", out, "--force"],
               ["signals", MACHINE, "--rundown", "60:55:5", "--out", out, "--force"]]
    a1, a2 = rng.choice(writers), rng.choice(writers)
    return {"argv": a1, "second": a2, "out": out, "shared_out": out, "out_replaced": True,
            "keep_in_out": out + "/my-notes.txt", "expect": "any", "both_may_win": True,
            "command": f"{a1[0]}+{a2[0]} --force", "what": f"{a1[0]} and {a2[0]} --force at once onto one run"}


@builder3
def sigint_mid_write(d):
    """SIGINT (Ctrl-C) after a random delay, onto a new --out or with
    --force over an existing run: the old run is intact or the new one is
    complete, and nothing is left beside --out."""
    out = d + "/out"
    force = rng.random() < 0.5
    if force:
        p = run(["simulate", MACHINE, "--speeds", "5:60:5", "--out", out])
        if p.returncode != 0:
            return {"argv": ["simulate"], "out": d + "/none", "expect": "any", "command": "simulate",
                    "what": "(setup failed)"}
    r = copy_run(d)
    which = rng.choice(["simulate", "signals", "plot", "report", "import", "diagnose-plots"])
    if which == "simulate":
        argv = ["simulate", MACHINE, "--speeds", "5:200:0.5", "--out", out]
    elif which == "signals":
        argv = ["signals", MACHINE, "--rundown", "60:30:5", "--out", out]
    elif which in ("plot", "report"):
        argv = [which, r, "--out", out]
    elif which == "import":
        i = copy_field(d)
        argv = ["import", i + "/vector-table.csv", "--layout", i + "/layout.toml", "--bearings",
                i + "/bearings.csv", "--out", out, "--plots"]
    else:
        argv = ["diagnose", r, "--plots", out]
    if force:
        argv.append("--force")
    delay = rng.choice([0.05, 0.2, 0.5, 1.0, 2.0])
    return {"argv": argv, "out": d + "/none", "atomic_out": out, "interrupt_after": delay, "expect": "any",
            "command": which.split("-")[0], "what": f"SIGINT after {delay} s ({'--force over a run' if force else 'new --out'})"}


# --------------------------------------------------- every other command
@builder3
def stream_adc_twice(d):
    """A stream configuration naming one ADC input twice, or one channel
    for two bearings."""
    r = copy_run(d)
    s = 'bearings = "bearings.csv"\n'
    style = rng.choice(["adc-twice", "same-place-twice"])
    for b, bearing in enumerate(["left", "right"]):
        for q, quantity in enumerate(["rel_y", "rel_z", "ped_y", "ped_z"]):
            adc = 4 * b + q
            if style == "adc-twice" and adc == 5:
                adc = 4
            qq = quantity
            if style == "same-place-twice" and adc == 3:
                qq = "ped_y"
            s += (f'\n[[channels]]\nadc = {adc}\nbearing = "{bearing}"\nquantity = "{qq}"\n'
                  'sensor = "proximity"\nsensitivity = 7870.0\n')
    open(r + "/stream.toml", "w").write(s)
    open(r + "/raw.bin", "wb").write(bytes(rng.randrange(256) for _ in range(4096)))
    return {"argv": ["stream", "--offline", "--config", r + "/stream.toml", "--out", d + "/out"],
            "out": d + "/out", "expect": "error", "command": "stream", "what": f"stream.toml: {style}"}


@builder3
def predict_and_paper_numbers(d):
    """accuracy, paper, demo and predict with numbers at the ends of the
    doubles in their options."""
    which = rng.choice(["accuracy-noise", "accuracy-speeds", "paper-speeds", "demo-rundown", "simulate-noise",
                        "signals-rate"])
    v = rng.choice(["1e-320", "4.9e-324", "1e308", "0x10", "1_000", "+5"])
    if which == "accuracy-noise":
        argv = ["accuracy", MACHINE, "--draws", "2", "--speeds", "5:60:5", "--noise", v]
    elif which == "accuracy-speeds":
        argv = ["accuracy", MACHINE, "--draws", "2", "--speeds", f"5:60:{v}"]
    elif which == "paper-speeds":
        argv = ["paper", "--speeds", f"{v}:60:5"]
    elif which == "demo-rundown":
        argv = ["demo", "--rundown", f"60:50:{v}", "--out", d + "/out"]
    elif which == "simulate-noise":
        argv = ["simulate", MACHINE, "--speeds", "5:60:5", "--noise", v, "--out", d + "/out"]
    else:
        argv = ["signals", MACHINE, "--rundown", "60:55:5", "--rate", v, "--out", d + "/out"]
    exp = "any" if v == "+5" else "error"
    if which == "simulate-noise" and v in ("1e-320", "4.9e-324"):
        exp = "any"  # simulate takes 0 (no noise); a subnormal fraction is no noise either
    return {"argv": argv, "out": d + "/out", "expect": exp, "command": which.split("-")[0],
            "what": f"{which} = {v}"}


main(P3)
