"""The cases and the runner of scripts/probe-inputs-2.sh (read its header).

Each builder makes one case in its own directory from clean copies of the
bundled examples and returns what to run and what the case expects. Cases
go round the builders (every builder runs at least once when CASES is at
least their number), each drawing its variant from the seeded generator.
"""
import hashlib
import json
import math
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import threading

PLINTH, ROOT, W = os.environ["PLINTH"], os.environ["ROOT"], os.environ["W"]
CASES, SEED, LIMIT = int(os.environ["CASES"]), int(os.environ["SEED"]), float(os.environ["LIMIT"])
EX = os.path.join(ROOT, "examples")
F = os.path.join(EX, "field")
MACHINE = os.path.join(EX, "feng-hahn-1997.toml")
SKID = os.path.join(EX, "two-pedestals-on-skid.toml")
rng = random.Random(SEED)


def run(argv, env=None, cwd=None, timeout=None):
    e = dict(os.environ)
    e.update(env or {})
    return subprocess.run([PLINTH, "--quiet"] + argv, cwd=cwd or W, env=e, capture_output=True,
                          stdin=subprocess.DEVNULL, timeout=timeout)


def must(argv):
    p = run(argv)
    if p.returncode != 0:
        sys.exit(f"baseline failed: {argv}: {p.stderr.decode()}")
    return p.stdout.decode()


# ---------------------------------------------------------------- baselines
must(["simulate", MACHINE, "--speeds", "5:60:1", "--out", W + "/base-run"])
must(["import", F + "/vector-table.csv", "--layout", F + "/layout.toml", "--bearings",
      F + "/bearings.csv", "--out", W + "/base-import"])
BASE_IDENTIFY = must(["identify", W + "/base-run", "--json"])


def wav_to_csv(src, dst):
    b = open(src, "rb").read()
    ch = struct.unpack("<H", b[22:24])[0]
    rate = struct.unpack("<I", b[24:28])[0]
    bits = struct.unpack("<H", b[34:36])[0]
    at = b.index(b"data") + 8
    w = bits // 8
    rows = ["time_s," + ",".join(f"c{i}" for i in range(ch))]
    for k, i in enumerate(range(at, len(b) - ch * w + 1, ch * w)):
        v = [int.from_bytes(b[i + j * w:i + (j + 1) * w], "little", signed=True) * 10.0 / 2 ** (bits - 1)
             for j in range(ch)]
        rows.append(f"{k / rate:.9f}," + ",".join(f"{x:.6f}" for x in v))
    open(dst, "w").write("\n".join(rows) + "\n")


wav_to_csv(F + "/recording.wav", W + "/recording.csv")
must(["extract", W + "/recording.csv", "--channels", F + "/channels.toml", "--bearings",
      F + "/bearings.csv", "--out", W + "/base-extract"])


# ------------------------------------------------------------------ helpers
def csv_rows(path):
    text = open(path, encoding="utf-8").read()
    return [l.split(",") for l in text.split("\n") if l != ""]


def write_rows(path, rows, end="\n", final=True):
    text = end.join(",".join(r) for r in rows)
    open(path, "w", encoding="utf-8", newline="").write(text + (end if final else ""))


def copy_field(d):
    """Clean copies of the field example's inputs in d/in."""
    i = os.path.join(d, "in")
    shutil.copytree(F, i)
    return i


def copy_run(d, name="run"):
    r = os.path.join(d, name)
    shutil.copytree(W + "/base-run", r)
    return r


def import_case(d, expect="any", compare=True, **kw):
    i = copy_field(d)
    c = {"argv": ["import", i + "/vector-table.csv", "--layout", i + "/layout.toml",
                  "--bearings", i + "/bearings.csv", "--out", d + "/out"],
         "out": d + "/out", "expect": expect, "command": "import"}
    if expect == "neutral" and compare:
        c["compare"] = ("file", "measurements.csv", W + "/base-import/measurements.csv")
    c.update(kw)
    return c, i


def identify_case(d, expect="any", cmd="identify", **kw):
    r = copy_run(d)
    if cmd == "identify":
        argv = ["identify", r, "--json"]
        out = d + "/out"
    elif cmd == "diagnose":
        argv = ["diagnose", r]
        out = d + "/out"
    elif cmd == "plot":
        argv = ["plot", r, "--out", d + "/out"]
        out = d + "/out"
    else:
        argv = ["report", r, "--out", d + "/out"]
        out = d + "/out"
    c = {"argv": argv, "out": out, "expect": expect, "command": cmd}
    if expect == "neutral" and cmd == "identify":
        c["compare"] = ("stdout", BASE_IDENTIFY)
    c.update(kw)
    return c, r


def extract_case(d, expect="any", csv=True, **kw):
    i = copy_field(d)
    rec = i + "/recording.csv"
    if csv:
        shutil.copy(W + "/recording.csv", rec)
    else:
        rec = i + "/recording.wav"
    c = {"argv": ["extract", rec, "--channels", i + "/channels.toml", "--bearings", i + "/bearings.csv",
                  "--out", d + "/out"], "out": d + "/out", "expect": expect, "command": "extract"}
    if expect == "neutral" and csv:
        c["compare"] = ("file", "measurements.csv", W + "/base-extract/measurements.csv")
    c.update(kw)
    return c, i, rec


def machine_case(d, text, expect="error"):
    m = os.path.join(d, "machine.toml")
    open(m, "w").write(text)
    which = rng.choice(["simulate", "simulate", "accuracy", "signals", "diagnose", "paper", "demo"])
    if which == "simulate":
        argv = ["simulate", m, "--speeds", "5:60:5", "--out", d + "/out"]
    elif which == "accuracy":
        argv = ["accuracy", m, "--draws", "2", "--speeds", "5:60:5"]
    elif which == "signals":
        argv = ["signals", m, "--rundown", "60:50:5", "--out", d + "/out"]
    elif which == "diagnose":
        r = copy_run(d)
        argv = ["diagnose", r, "--machine", m]
    elif which == "paper":
        argv = ["paper", "--machine", m, "--speeds", "5:60:5"]
    else:
        argv = ["demo", "--machine", m, "--rundown", "60:50:5", "--out", d + "/out"]
    return {"argv": argv, "out": d + "/out", "expect": expect, "command": which}


MACHINE_TEXT = open(MACHINE).read()


def machine_edit(old, new, count=1):
    assert old in MACHINE_TEXT, old
    return MACHINE_TEXT.replace(old, new, count)


def table_header_index(rows, pred):
    return [j for j, h in enumerate(rows[0]) if pred(h)]


# ------------------------------------------------------------------ builders
B = []


def builder(f):
    B.append(f)
    return f


# --- import: spreadsheet dialects (neutral: same run as the clean table)
@builder
def import_reordered_extra_columns(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    order = list(range(len(rows[0])))
    rng.shuffle(order)
    rows = [[r[j] for j in order] for r in rows]
    extra = rng.choice([["Comment", "Temp (C)"], ["Unnamed: 0"], ["left 45L 1X Amp (old)", "Alarm"]])
    rows = [r + (extra if k == 0 else [rng.choice(["", "ok", "21.5"]) for _ in extra]) for k, r in enumerate(rows)]
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"table columns shuffled + unknown columns {extra}"
    return c


@builder
def import_quoted_numbers(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    rows = [r if k == 0 else [f'"{x}"' for x in r] for k, r in enumerate(rows)]
    if rng.random() < 0.5:
        rows[0] = [f'"{x}"' for x in rows[0]]
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = "every number quoted (Excel CSV)"
    return c


@builder
def import_thousands_separator(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    j = rows[0].index("Speed (rpm)")
    style = rng.choice(["quoted-comma", "space", "apostrophe", "unquoted-comma"])
    for r in rows[1:]:
        v = int(float(r[j]))
        if v >= 1000:
            s = f"{v:,}"
            r[j] = {"quoted-comma": f'"{s}"', "space": s.replace(",", " "),
                    "apostrophe": s.replace(",", "'"), "unquoted-comma": s}[style]
    write_rows(i + "/vector-table.csv", rows)
    if style != "quoted-comma":
        c["expect"] = "error"
    c["what"] = f"speeds with thousands separators ({style})"
    return c


@builder
def import_trailing_empty_columns(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    n = rng.choice([1, 3])
    rows = [r + [""] * n for r in rows]
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"{n} trailing empty columns on every line"
    return c


@builder
def import_na_cell(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(1, len(rows))
    j = rng.randrange(1, len(rows[0]))
    rows[k][j] = rng.choice(["#N/A", "#VALUE!", "#DIV/0!", "N/A", "-", "---"])
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"{rows[k][j]} at line {k + 1} column {rows[0][j]!r}"
    c["names_line"] = True
    return c


@builder
def import_trailing_spaces(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    head = rng.random() < 0.5
    rows = [[x + " " if (k > 0 or head) else x for x in r] for k, r in enumerate(rows)]
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = "trailing spaces in every cell" + (" and the header" if head else "")
    return c


@builder
def import_no_final_newline_crlf_bom(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    style = rng.choice(["no-final-newline", "crlf-no-final", "excel-all"])
    if style == "excel-all":
        rows = [r if k == 0 else [f'"{x}"' for x in r] + ["", ""] for k, r in enumerate(rows)]
        rows[0] = rows[0] + ["", ""]
        text = "\r\n".join(",".join(r) for r in rows)
        open(i + "/vector-table.csv", "wb").write(b"\xef\xbb\xbf" + text.encode())
    else:
        write_rows(i + "/vector-table.csv", rows, "\r\n" if style == "crlf-no-final" else "\n", final=False)
    c["what"] = f"table {style}"
    return c


@builder
def import_units_row_or_comments(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/vector-table.csv")
    style = rng.choice(["units-row", "comment-lines", "title-line"])
    if style == "units-row":
        rows.insert(1, ["", "rpm"] + ["um pp" if "Amp" in h else "deg" for h in rows[0][2:]])
    elif style == "comment-lines":
        rows = [["# Exported by ADRE 408"], ["# Machine: BFP-A"]] + rows
    else:
        rows = [["Run-down 3 May 2025"]] + rows
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"table with {style}"
    c["names_line"] = True
    return c


@builder
def import_phase_radians(d):
    c, i = import_case(d, "warn")
    rows = csv_rows(i + "/vector-table.csv")
    for j in table_header_index(rows, lambda h: "Phase" in h):
        for r in rows[1:]:
            r[j] = f"{math.radians(float(r[j])):.4f}"
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = "phases written in radians where the layout says degrees"
    return c


@builder
def import_phase_wrapped(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    style = rng.choice(["+360", "+720", "-360"])
    add = {"+360": 360, "+720": 720, "-360": -360}[style]
    for j in table_header_index(rows, lambda h: "Phase" in h):
        for r in rows[1:]:
            r[j] = f"{float(r[j]) + add:g}"
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"phases {style} (same angle)"
    c["compare"] = ("phasors", "measurements.csv", W + "/base-import/measurements.csv")
    return c


@builder
def import_speed_repeated(d):
    c, i = import_case(d, "warn")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(2, len(rows) - 1)
    dup = list(rows[k])
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h))
    dup[j] = f"{float(dup[j]) * 1.7:.3g}"
    rows.insert(k + 1, dup)
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"speed {dup[1]} rpm twice with different amplitudes"
    return c


@builder
def import_speed_shuffled(d):
    c, i = import_case(d, "neutral")
    rows = csv_rows(i + "/vector-table.csv")
    body = rows[1:]
    rng.shuffle(body)
    write_rows(i + "/vector-table.csv", [rows[0]] + body)
    c["what"] = "rows in random order (speeds not monotonic)"
    c["compare"] = ("sorted", "measurements.csv", W + "/base-import/measurements.csv")
    return c


@builder
def import_speed_zero_negative(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(1, len(rows))
    rows[k][1] = rng.choice(["0", "-0", "-1500", "1e-300", "-4500"])
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"speed {rows[k][1]} rpm at line {k + 1}"
    c["names_line"] = True
    if rows[k][1] in ("0", "-0", "1e-300"):
        c["expect"] = "warn"
    return c


@builder
def import_huge_exponent(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(1, len(rows))
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h or "Phase" in h))
    rows[k][j] = rng.choice(["1e308", "9e307", "1.0E+300", "1e-308", "4.9e-324"])
    write_rows(i + "/vector-table.csv", rows)
    if "Phase" in rows[0][j] or rows[k][j] in ("1e-308", "4.9e-324"):
        c["expect"] = "any"
    c["what"] = f"{rows[k][j]} at line {k + 1} column {rows[0][j]!r}"
    c["names_line"] = c["expect"] == "error"
    return c


@builder
def import_unit_in_cell(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(1, len(rows))
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h))
    rows[k][j] = rows[k][j] + rng.choice([" um", "um", " µm pp", "mm/s"])
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"a unit inside the cell: {rows[k][j]!r} at line {k + 1}"
    c["names_line"] = True
    return c


@builder
def import_blank_row(d):
    c, i = import_case(d, "any")
    rows = csv_rows(i + "/vector-table.csv")
    k = rng.randrange(2, len(rows))
    rows.insert(k, [""] * rng.choice([len(rows[0]), 1]))
    write_rows(i + "/vector-table.csv", rows)
    c["what"] = f"an empty row at line {k + 1}"
    return c


@builder
def import_layout_bad(d):
    c, i = import_case(d, "error")
    t = open(i + "/layout.toml").read()
    style = rng.choice(["missing-column", "unit", "speed-unit", "same-angle", "unknown-bearing",
                        "angle-400", "angle-nan", "phase-convention", "column-twice"])
    if style == "missing-column":
        t = t.replace('"left 45R 1X Amp"', '"left 45R 1X Ampl"')
    elif style == "unit":
        t = t.replace('unit = "um pp" }', 'unit = "um p-p" }', 1)
        c["expect"] = "neutral"  # `p-p` is a documented alias of `pp`
    elif style == "speed-unit":
        t = t.replace('unit = "rpm"', 'unit = "rad/s"')
    elif style == "same-angle":
        t = t.replace('angle = "45R"', 'angle = "45L"', 1)
    elif style == "unknown-bearing":
        t = t.replace('bearing = "left"', 'bearing = "middle"', 1)
    elif style == "angle-400":
        t = t.replace("angle_deg = 90.0", "angle_deg = 450.0", 1)
        c["expect"] = "neutral"  # the same axis; cos(450°) differs in the last digit
        c["compare"] = ("phasors", "measurements.csv", W + "/base-import/measurements.csv")
    elif style == "angle-nan":
        t = t.replace("angle_deg = 90.0", "angle_deg = nan", 1)
    elif style == "phase-convention":
        t = t.replace('phase = "lag"', 'phase = "lagging"')
    else:
        t = t.replace('"left 45R 1X Amp"', '"left 45L 1X Amp"')
    open(i + "/layout.toml", "w").write(t)
    c["what"] = f"layout: {style}"
    return c


@builder
def import_bearings_mismatch(d):
    c, i = import_case(d, "error")
    rows = csv_rows(i + "/bearings.csv")
    style = rng.choice(["case", "renamed", "range", "duplicate", "extra-bearing"])
    if style == "case":
        for r in rows[1:]:
            r[1] = r[1].capitalize()
    elif style == "renamed":
        for r in rows[1:]:
            r[1] = {"left": "DE", "right": "NDE"}.get(r[1], r[1])
    elif style == "range":
        rows = [rows[0]] + [r for r in rows[1:] if float(r[0]) <= 40]
    elif style == "duplicate":
        k = rng.randrange(1, len(rows))
        dup = list(rows[k])
        dup[2] = str(float(dup[2]) * 2)
        rows.insert(k + 1, dup)
    else:
        rows += [[r[0], "middle"] + r[2:] for r in rows[1:] if r[1] == "left"]
        c["expect"] = "any"
    write_rows(i + "/bearings.csv", rows)
    c["what"] = f"bearings.csv: {style}"
    return c


@builder
def import_million_rows(d):
    c, i = import_case(d, "any")
    rows = csv_rows(i + "/vector-table.csv")
    body = rows[1:]
    with open(i + "/vector-table.csv", "w") as f:
        f.write(",".join(rows[0]) + "\n")
        for n in range(1_000_000):
            r = body[n % len(body)]
            f.write(f"{n},{4500 - n * 4000 / 1_000_000:.4f}," + ",".join(r[2:]) + "\n")
    mb = rng.choice(["64", "256"])
    c["env"] = {"PLINTH_MEMORY_MB": mb}
    c["what"] = f"table of 10^6 rows, PLINTH_MEMORY_MB={mb}"
    return c


# --- run directories
@builder
def run_reordered_columns(d):
    cmd = rng.choice(["identify", "identify", "plot", "report"])
    c, r = identify_case(d, "neutral", cmd)
    rows = csv_rows(r + "/measurements.csv")
    order = list(range(len(rows[0])))
    rng.shuffle(order)
    rows = [[x[j] for j in order] for x in rows]
    if rng.random() < 0.6:
        rows = [x + (["comment"] if k == 0 else ["x"]) for k, x in enumerate(rows)]
    write_rows(r + "/measurements.csv", rows)
    c["what"] = "measurements.csv columns shuffled" + (" + unknown column" if rows[0][-1] == "comment" else "")
    return c


@builder
def run_truth_disagrees(d):
    cmd = rng.choice(["identify", "diagnose", "report"])
    c, r = identify_case(d, "warn", cmd)
    t = json.load(open(r + "/truth.json"))
    style = rng.choice(["renamed", "missing-pedestal", "extra-pedestal", "nan", "string", "array", "case"])
    if style == "renamed":
        t["pedestals"][0]["bearing"] = "DE"
    elif style == "missing-pedestal":
        # A truth may list only the pedestals it made (a bearing without
        # one is measured but has no truth): nothing to compare, not wrong.
        t["pedestals"] = t["pedestals"][:1]
        c["expect"] = "any"
    elif style == "extra-pedestal":
        t["pedestals"].append(dict(t["pedestals"][0], bearing="middle"))
    elif style == "case":
        t["pedestals"][0]["bearing"] = t["pedestals"][0]["bearing"].upper()
    elif style == "string":
        t["pedestals"][0]["k_y"] = "1e7"
        c["expect"] = "error"
    elif style == "array":
        t = [t]
        c["expect"] = "error"
    text = json.dumps(t)
    if style == "nan":
        text = text.replace(str(t["pedestals"][0]["m"]), "NaN", 1)
        c["expect"] = "error"
    open(r + "/truth.json", "w").write(text)
    c["what"] = f"truth.json: {style}"
    return c


@builder
def run_bearings_disagree(d):
    cmd = rng.choice(["identify", "diagnose", "plot", "report"])
    c, r = identify_case(d, "error", cmd)
    rows = csv_rows(r + "/bearings.csv")
    style = rng.choice(["case", "renamed", "range", "duplicate-different", "descending"])
    if style == "case":
        for x in rows[1:]:
            x[1] = x[1].upper()
    elif style == "renamed":
        for x in rows[1:]:
            x[1] = x[1] + "_brg"
    elif style == "range":
        rows = [rows[0]] + [x for x in rows[1:] if float(x[0]) >= 20]
    elif style == "duplicate-different":
        k = rng.randrange(1, len(rows))
        dup = list(rows[k])
        dup[2] = str(float(dup[2]) * 3)
        rows.insert(k + 1, dup)
    else:
        rows = [rows[0]] + rows[1:][::-1]
        c["expect"] = "neutral"
    write_rows(r + "/bearings.csv", rows)
    c["what"] = f"bearings.csv: {style}"
    return c


@builder
def run_measurements_values(d):
    cmd = rng.choice(["identify", "identify", "diagnose", "plot"])
    c, r = identify_case(d, "error", cmd)
    rows = csv_rows(r + "/measurements.csv")
    style = rng.choice(["dup-different", "speed-0", "speed-negative", "huge", "case-name",
                        "dead-bearing", "one-speed", "three-speeds", "missing-rows"])
    k = rng.randrange(1, len(rows))
    if style == "dup-different":
        dup = list(rows[k])
        dup[2] = repr(float(dup[2]) * 1.5 + 1e-9)
        rows.insert(k + 1, dup)
    elif style == "speed-0":
        rows[k][0] = "0"
        c["expect"] = "warn"
    elif style == "speed-negative":
        rows[k][0] = "-" + rows[k][0]
    elif style == "huge":
        rows[k][rng.randrange(2, len(rows[0]))] = rng.choice(["1e308", "-1.7e308"])
    elif style == "case-name":
        for x in rows[1:]:
            if x[1] == "left":
                x[1] = "Left"
    elif style == "dead-bearing":
        for x in rows[1:]:
            if x[1] == "right":
                x[2:] = ["0"] * (len(x) - 2)
        c["expect"] = "warn"  # a rank warning and UNTRUSTED (docs/robustness.md)
    elif style == "one-speed":
        rows = [rows[0]] + [x for x in rows[1:] if x[0] == "30"]
    elif style == "three-speeds":
        rows = [rows[0]] + [x for x in rows[1:] if x[0] in ("10", "30", "50")]
        c["expect"] = "warn" if cmd != "plot" else "any"
    else:
        rows = [x for x in rows if not (x[1] == "right" and x[0] not in ("1",) and float(x[0] if x[0][0].isdigit() else 0) > 30)]
        c["expect"] = "any"
    write_rows(r + "/measurements.csv", rows)
    c["what"] = f"measurements.csv: {style}"
    return c


@builder
def run_sd_columns(d):
    c, r = identify_case(d, "error", rng.choice(["identify", "diagnose"]))
    rows = csv_rows(r + "/measurements.csv")
    style = rng.choice(["two-of-four", "negative", "zero", "nan"])
    names = ["rel_y_sd", "rel_z_sd"] if style == "two-of-four" else ["rel_y_sd", "rel_z_sd", "ped_y_sd", "ped_z_sd"]
    value = {"two-of-four": "1e-9", "negative": "-1e-9", "zero": "0", "nan": "NaN"}[style]
    rows = [x + (names if k == 0 else [value] * len(names)) for k, x in enumerate(rows)]
    write_rows(r + "/measurements.csv", rows)
    c["what"] = f"measurements.csv *_sd columns: {style}"
    return c


@builder
def run_dialects(d):
    c, r = identify_case(d, "neutral", "identify")
    rows = csv_rows(r + "/measurements.csv")
    style = rng.choice(["no-final-newline", "crlf", "trailing-spaces", "quoted", "blank-lines-end"])
    if style == "no-final-newline":
        write_rows(r + "/measurements.csv", rows, final=False)
    elif style == "crlf":
        write_rows(r + "/measurements.csv", rows, "\r\n")
    elif style == "trailing-spaces":
        write_rows(r + "/measurements.csv", [[x + " " for x in y] for y in rows])
    elif style == "quoted":
        write_rows(r + "/measurements.csv", [y if k == 0 else [f'"{x}"' for x in y] for k, y in enumerate(rows)])
    else:
        write_rows(r + "/measurements.csv", rows)
        open(r + "/measurements.csv", "a").write("\n\n\n")
    c["what"] = f"measurements.csv {style}"
    return c


@builder
def run_million_rows(d):
    cmd = rng.choice(["identify", "plot"])
    c, r = identify_case(d, "any", cmd)
    rows = csv_rows(r + "/measurements.csv")
    with open(r + "/measurements.csv", "w") as f:
        f.write(",".join(rows[0]) + "\n")
        for n in range(500_000):
            s = 5 + n * 55 / 500_000
            for b in ("left", "right"):
                f.write(f"{s:.6f},{b},1e-6,2e-6,3e-6,4e-6,1e-7,2e-7,3e-7,4e-7\n")
    mb = rng.choice(["64", "512"])
    c["env"] = {"PLINTH_MEMORY_MB": mb}
    c["what"] = f"measurements.csv of 10^6 rows, PLINTH_MEMORY_MB={mb}"
    return c


@builder
def run_dir_shapes(d):
    style = rng.choice(["file", "empty", "only-truth", "nested"])
    cmd = rng.choice(["identify", "diagnose", "plot", "report"])
    c, r = identify_case(d, "error", cmd)
    if style == "file":
        shutil.rmtree(r)
        shutil.copy(W + "/base-run/measurements.csv", r)
    elif style == "empty":
        shutil.rmtree(r)
        os.mkdir(r)
    elif style == "only-truth":
        os.remove(r + "/measurements.csv")
        os.remove(r + "/bearings.csv")
    else:
        shutil.move(r, d + "/tmp")
        os.mkdir(r)
        shutil.move(d + "/tmp", r + "/run-3-may")
    c["what"] = f"run directory: {style}"
    return c


@builder
def run_options(d):
    cmd = rng.choice(["identify", "diagnose", "report"])
    c, r = identify_case(d, "error", cmd)
    opts = {
        "identify": [["--speeds", "60:5"], ["--speeds", "1e9:2e9"], ["--speeds", "30:30"], ["--slow-roll", "1:2"],
                     ["--model", "k_y,k_y,m"], ["--model", ""], ["--model", "k_y,foo"], ["--model", "m"],
                     ["--max-condition", "-1"], ["--max-condition", "nan"],
                     ["--unmeasured-base", "left,nosuch"], ["--unmeasured-base", "left"],
                     ["--plots", r + "/measurements.csv"]],
        "diagnose": [["--base", "k_y,zzz"], ["--base", ""], ["--alpha", "0"], ["--speeds", "100:5"],
                     ["--machine", SKID], ["--plots", r]],
        "report": [["--speeds", "1e9:2e9"], ["--unmeasured-base", ";"], ["--unmeasured-base", "left;left"]],
    }[cmd]
    o = rng.choice(opts)
    c["argv"] = c["argv"] + o
    if o == ["--speeds", "30:30"] or o == ["--model", "m"]:
        c["expect"] = "warn"
    if o in (["--machine", SKID], ["--unmeasured-base", "left"]):
        c["expect"] = "any"  # same bearings (see diagnose_other_machine); a base under one pedestal
    c["what"] = "option " + " ".join(o)
    return c


@builder
def diagnose_other_machine(d):
    r = copy_run(d)
    style = rng.choice(["skid", "moved-bearing", "renamed", "stiffer"])
    m = d + "/machine.toml"
    if style == "skid":
        # The same rotor and bearings on a skid: the identified model, not
        # the file, decides what the pedestals stand on (diagnose/machine.rs).
        shutil.copy(SKID, m)
        exp = "any"
    elif style == "moved-bearing":
        open(m, "w").write(machine_edit("position = 1.1", "position = 0.9"))
        exp = "warn"
    elif style == "renamed":
        open(m, "w").write(machine_edit('name = "left"', 'name = "DE"'))
        exp = "error"
    else:
        open(m, "w").write(machine_edit("young_modulus = 2.11e11", "young_modulus = 2.11e13"))
        exp = "warn"
    return {"argv": ["diagnose", r, "--machine", m], "out": d + "/out", "expect": exp, "command": "diagnose",
            "what": f"diagnose --machine: {style}"}


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


@builder
def extract_channels_bad(d):
    c, i, rec = extract_case(d, "error", csv=rng.random() < 0.5)
    t = open(i + "/channels.toml").read()
    style = rng.choice(["index-99", "keyphasor-99", "dup-index", "full-scale-0", "full-scale-neg",
                        "revolutions-0", "revolutions-huge", "threshold-never", "sensitivity-0",
                        "speed-resolution-0", "unknown-bearing"])
    if style == "index-99":
        t = t.replace("index = 7", "index = 99")
    elif style == "keyphasor-99":
        t = t.replace("channel = 8", "channel = 99")
    elif style == "dup-index":
        t = t.replace("index = 7", "index = 6")
    elif style == "full-scale-0":
        t = t.replace("full_scale_v = 10.0", "full_scale_v = 0.0")
    elif style == "full-scale-neg":
        t = t.replace("full_scale_v = 10.0", "full_scale_v = -10.0")
    elif style == "revolutions-0":
        t = t.replace("revolutions = 4", "revolutions = 0")
    elif style == "revolutions-huge":
        t = t.replace("revolutions = 4", "revolutions = 1000000000")
    elif style == "threshold-never":
        t = t.replace("threshold_v = -5.0", "threshold_v = -50.0")
    elif style == "sensitivity-0":
        t = t.replace("sensitivity = 7.87", "sensitivity = 0.0", 1)
    elif style == "speed-resolution-0":
        t = "speed_resolution_hz = 0.0\n" + t
    else:
        t = t.replace('bearing = "right"', 'bearing = "middle"', 1)
    open(i + "/channels.toml", "w").write(t)
    c["what"] = f"channels.toml: {style} ({os.path.basename(rec)})"
    return c


@builder
def extract_csv_recording(d):
    c, i, rec = extract_case(d, "error", csv=True)
    rows = csv_rows(rec)
    style = rng.choice(["time-backwards", "time-repeated", "no-time", "jitter", "nan-sample", "huge-sample",
                        "reordered-columns", "quoted", "crlf-no-final", "extra-column", "rate-halved"])
    k = rng.randrange(100, len(rows) - 100)
    if style == "time-backwards":
        rows[k][0], rows[k + 1][0] = rows[k + 1][0], rows[k][0]
    elif style == "time-repeated":
        rows[k][0] = rows[k - 1][0]
    elif style == "no-time":
        rows = [x[1:] for x in rows]
    elif style == "jitter":
        for x in rows[1:]:
            x[0] = f"{float(x[0]) * (1 + rng.uniform(-2e-3, 2e-3)):.9f}"
    elif style == "nan-sample":
        rows[k][3] = "NaN"
    elif style == "huge-sample":
        rows[k][3] = "1e308"
    elif style == "reordered-columns":
        order = [0] + list(range(1, len(rows[0])))[::-1]
        rows = [[x[j] for j in order] for x in rows]
        c["expect"] = "neutral"
    elif style == "quoted":
        rows = [x if n == 0 else [f'"{v}"' for v in x] for n, x in enumerate(rows)]
        c["expect"] = "neutral"
    elif style == "crlf-no-final":
        write_rows(rec, rows, "\r\n", final=False)
        c["expect"] = "neutral"
        c["compare"] = ("file", "measurements.csv", W + "/base-extract/measurements.csv")
        c["what"] = f"recording.csv: {style}"
        return c
    elif style == "extra-column":
        rows = [x + (["temperature"] if n == 0 else ["21.5"]) for n, x in enumerate(rows)]
        c["expect"] = "neutral"
    else:
        rows = [rows[0]] + [x for n, x in enumerate(rows[1:]) if n % 2 == 0]
        c["expect"] = "any"
    if c["expect"] == "neutral":
        c["compare"] = ("file", "measurements.csv", W + "/base-extract/measurements.csv")
    write_rows(rec, rows)
    c["what"] = f"recording.csv: {style}"
    return c


# --- --out and concurrency
def some_writer(d, out):
    which = rng.choice(["simulate", "import", "plot", "report", "signals", "extract"])
    if which == "simulate":
        return which, ["simulate", MACHINE, "--speeds", "5:60:5", "--out", out]
    if which == "signals":
        return which, ["signals", MACHINE, "--rundown", "60:55:5", "--out", out]
    if which == "import":
        i = d + "/in-import"
        if not os.path.isdir(i):
            shutil.copytree(F, i)
        return which, ["import", i + "/vector-table.csv", "--layout", i + "/layout.toml",
                       "--bearings", i + "/bearings.csv", "--out", out, "--plots"]
    if which == "extract":
        i = d + "/in-extract"
        if not os.path.isdir(i):
            shutil.copytree(F, i)
        return which, ["extract", i + "/recording.wav", "--channels", i + "/channels.toml",
                       "--bearings", i + "/bearings.csv", "--out", out]
    r = d + "/run"
    if not os.path.isdir(r):
        shutil.copytree(W + "/base-run", r)
    return which, [which, r, "--out", out]


@builder
def out_hostile(d):
    style = rng.choice(["existing-file", "input-file", "inside-input-dir", "parent-of-inputs", "empty-string",
                        "trailing-slash", "deep-new", "dev-null", "read-only-parent", "out-dotdot-into-input"])
    out = d + "/out"
    exp = "error"
    os.mkdir(d + "/in")
    open(d + "/in/precious.txt", "w").write("do not lose me\n")
    if style == "existing-file":
        open(out, "w").write("precious\n")
    elif style == "inside-input-dir":
        exp = "any"
    elif style == "empty-string":
        out = ""
    elif style == "trailing-slash":
        exp = "any"
    elif style == "deep-new":
        out = d + "/a/b/c/out"
        exp = "any"
    elif style == "dev-null":
        out = "/dev/null"
    elif style == "read-only-parent":
        os.mkdir(d + "/ro")
        os.chmod(d + "/ro", 0o555)
        out = d + "/ro/out"
        if os.geteuid() == 0:
            exp = "any"  # root writes into a read-only directory
    which, argv = some_writer(d, out if style not in ("trailing-slash", "inside-input-dir") else "PLACEHOLDER")
    if style == "input-file":
        inputs = [a for a in argv if os.path.isfile(a)]
        out = inputs[0] if inputs else d + "/in/precious.txt"
    elif style == "inside-input-dir":
        inputs = [a for a in argv[1:] if os.path.exists(a) and a.startswith(d)]
        base = os.path.dirname(inputs[0]) if inputs and os.path.isfile(inputs[0]) else (inputs[0] if inputs else d + "/in")
        out = base + "/results"
    elif style == "parent-of-inputs":
        out = d
    elif style == "trailing-slash":
        out = d + "/out/"
    elif style == "out-dotdot-into-input":
        inputs = [a for a in argv[1:] if os.path.exists(a) and a.startswith(d)]
        out = (os.path.dirname(inputs[0]) if inputs and os.path.isfile(inputs[0]) else d + "/in") + "/../out/.."
    argv = [out if a == "PLACEHOLDER" or a == argv[argv.index("--out") + 1] else a for a in argv]
    return {"argv": argv, "out": out if style in ("inside-input-dir", "trailing-slash", "deep-new", "read-only-parent") else d + "/none",
            "expect": exp, "command": which, "what": f"--out {style}", "chmod_back": d + "/ro"}


@builder
def out_concurrent(d):
    out = d + "/out"
    if rng.random() < 0.5:
        os.mkdir(out)  # the user made it empty beforehand
    w1, a1 = some_writer(d, out)
    w2, a2 = some_writer(d, out)
    return {"argv": a1, "second": a2, "out": d + "/none", "shared_out": out, "expect": "any",
            "command": f"{w1}+{w2}", "what": f"{w1} and {w2} at once into one --out"}


@builder
def out_force_over_other(d):
    """--force onto a run another command wrote: the other files kept?"""
    out = d + "/out"
    w1, a1 = some_writer(d, out)
    p = run(a1)
    if p.returncode != 0:
        return {"argv": a1, "out": d + "/none", "expect": "any", "command": w1, "what": "(setup failed)"}
    open(out + "/my-notes.txt", "w").write("mine\n")
    w2, a2 = some_writer(d, out)
    # --force replaces what Plinth wrote there: only the user's file is guarded.
    return {"argv": a2 + ["--force"], "out": out, "out_replaced": True,
            "keep_in_out": out + "/my-notes.txt",
            "expect": "any", "command": f"{w2} --force", "what": f"{w2} --force over {w1}'s run + a user file"}


@builder
def names_hostile(d):
    """Names from tables that reach file names (not the first probe's ../../x)."""
    c, r = identify_case(d, "error", rng.choice(["plot", "report", "identify"]))
    name = rng.choice(["CON", "a\u202eb", "left\u00a0", "x" * 65, "..", ".hidden", "left\tA", "名前", "lpt1",
                       "a*b", "a?b", "~", "-rf"])
    for fn in ("measurements.csv", "bearings.csv"):
        rows = csv_rows(r + "/" + fn)
        for x in rows[1:]:
            if x[1] == "left":
                x[1] = name
        write_rows(r + "/" + fn, rows)
    # A trailing no-break space is trimmed like any space (the same name in
    # both files); the others are letters a file system takes.
    if name in ("名前", "CON", "lpt1", "~", "-rf", "left\u00a0"):
        c["expect"] = "any"
    if c["command"] == "identify":
        c["argv"] += ["--plots", d + "/out"]
    c["what"] = f"bearing named {name!r}"
    return c


# ------------------------------------------------------------------- runner
def snapshot(d, exclude):
    seen = {}
    for root, dirs, files in os.walk(d):
        for f in files + dirs:
            p = os.path.join(root, f)
            if any(p == e or p.startswith(e.rstrip("/") + "/") for e in exclude):
                continue
            if os.path.islink(p):
                seen[p] = "link " + os.readlink(p)
            elif os.path.isfile(p):
                try:
                    seen[p] = hashlib.sha1(open(p, "rb").read()).hexdigest()
                except OSError:
                    seen[p] = "unreadable"
            elif os.path.isdir(p):
                seen[p] = "dir"
    return seen


def phasors(path):
    rows = csv_rows(path)
    out = {}
    for x in rows[1:]:
        out[(round(float(x[0]), 6), x[1])] = [float(v) for v in x[2:10]]
    return out


def compare(c, stdout):
    kind = c["compare"][0]
    if kind == "stdout":
        return stdout == c["compare"][1]
    produced = os.path.join(c["out"], c["compare"][1])
    if not os.path.isfile(produced):
        return False
    a, b = open(produced).read(), open(c["compare"][2]).read()
    if kind == "file":
        return a == b
    if kind == "sorted":
        return sorted(a.splitlines()) == sorted(b.splitlines())
    pa, pb = phasors(produced), phasors(c["compare"][2])
    if pa.keys() != pb.keys():
        return False
    for k in pa:
        scale = max(abs(v) for v in pb[k]) or 1.0
        if any(abs(x - y) > 1e-3 * scale for x, y in zip(pa[k], pb[k])):
            return False
    return True


def classify(c):
    d = c["dir"]
    # A --out that does not exist yet is the command's to fill; one that
    # exists (a file, a user's directory) is guarded like any other file.
    excl = [o for o in (c["out"], c.get("shared_out"))
            if o and not os.path.lexists(o) or (o and os.path.isdir(o) and not os.listdir(o))]
    if c.get("out_replaced"):
        excl.append(c["out"])
    excl = [o.rstrip("/") for o in excl]
    before = {p: h for p, h in snapshot(d, excl).items() if ".plinth-" not in p}
    shared = c.get("shared_out")
    keep = c.get("keep_in_out")
    keep_hash = hashlib.sha1(open(keep, "rb").read()).hexdigest() if keep else None
    results = [None, None]

    def one(k, argv):
        try:
            p = run(argv, env=c.get("env"), cwd=d, timeout=LIMIT)
            results[k] = (p.returncode, p.stdout.decode("utf-8", "replace"), p.stderr.decode("utf-8", "replace"))
        except subprocess.TimeoutExpired:
            results[k] = (None, "", "")

    threads = [threading.Thread(target=one, args=(0, c["argv"]))]
    if "second" in c:
        threads.append(threading.Thread(target=one, args=(1, c["second"])))
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if os.path.isdir(c.get("chmod_back") or "/nonexistent"):
        os.chmod(c["chmod_back"], 0o755)
    code, out, err = results[0]
    after = snapshot(d, excl)
    lost = sorted(os.path.relpath(p, d) for p, h in before.items() if after.get(p) != h)
    new = sorted(os.path.relpath(p, d) for p in after if p not in before and ".plinth-" not in p
                 and not any(p.startswith(x) for x in [d + "/out", d + "/a", d + "/tmp"])
                 and not (shared and p.startswith(shared)))
    if keep and (not os.path.isfile(keep) or hashlib.sha1(open(keep, "rb").read()).hexdigest() != keep_hash):
        lost.append(os.path.relpath(keep, d))
    if "second" in c:
        c2, o2, e2 = results[1]
        if c2 is None:
            code = None
        elif code == 0 and c2 == 0:
            lost.append("both writers exited 0 on one --out: " + "; ".join(sorted(os.listdir(shared)))[:200])
        elif code != 0 and c2 == 0:
            code, out, err = c2, o2, e2 + "\n(first) " + err
        elif code != 0 and c2 != 0:
            err = err + "\n(second) " + e2
        # The losing writer's message must name the --out.
        loser = e2 if c2 != 0 else (err if results[0][0] != 0 else "")
        if loser and shared not in loser and os.path.basename(shared) not in loser:
            err += "\n(loser does not name --out)"
    if code is None:
        return "hang", "", ""
    if lost:
        return "data-loss", "changed or removed: " + ", ".join(lost[:5]), err
    if new:
        return "outside-out", "new: " + ", ".join(new[:5]), err
    if "panicked" in err:
        return "panic", "", err
    if code < 0 or code >= 128:
        return "abort", f"exit {code}", err
    if code == 0:
        written = ""
        if c["out"] and os.path.isdir(c["out"]):
            for root, _, files in os.walk(c["out"]):
                for f in files:
                    if f.endswith((".csv", ".json")):
                        written += open(os.path.join(root, f), errors="replace").read()
        if re.search(r"(?<![A-Za-z_])(inf|NaN|nan)(?![A-Za-z_])", out + written):
            return "garbage", "inf/NaN in the output", err
        if c["expect"] == "error":
            return "garbage", "accepted (expected an error)", err
        judged = re.search(r'UNTRUSTED|NOT to be trusted|"trusted": ?false', out)
        if c["expect"] == "warn" and "warning" not in err and not judged:
            return "garbage", "accepted without a warning", err
        if c["expect"] == "neutral" and "compare" in c and not compare(c, out):
            return "garbage", "result differs from the clean input's", err
        return "ok", "", err
    last = [l for l in err.splitlines() if l.startswith("error:")]
    msg = last[-1] if last else err.strip()[-300:]
    if last and msg.rstrip().endswith(":"):  # clap lists what it means below
        msg = err.strip()[-300:]
    names_place = re.search(r"(\.csv|\.toml|\.wav|\.json|raw\.bin|--[a-z]|/)", msg)
    if c.get("names_line") and not re.search(r"line \d+|:\d+(:\d+)?:", msg):
        names_place = None
    if "(loser does not name --out)" in err:
        names_place = None
    return ("clear-error" if last and names_place else "unclear-error"), "", err


cases = []
for n in range(CASES):
    d = os.path.join(W, f"case{n:04d}")
    os.mkdir(d)
    b = B[n % len(B)]
    c = b(d)
    c["dir"] = d
    c["builder"] = b.__name__
    cases.append(c)

counts, notes = {}, []
log = open(os.path.join(W, "errors.txt"), "w")
for c in cases:
    cls, why, err = classify(c)
    counts[cls] = counts.get(cls, 0) + 1
    lines = (err.strip().splitlines() or ["(no message)"])
    shown = [l for l in lines if l.startswith("error:")] or lines
    log.write(f"{cls:14} {c['command']:18} {c['what']}\n    {' '.join(c['argv'])[:400]}\n    {shown[-1][:400]}\n")
    if cls not in ("ok", "clear-error"):
        notes.append(f"{cls:14} {c['command']:18} {c['what']}: {why} | {shown[-1][:300]}")
    if "--classes" in os.environ.get("PROBE_FLAGS", ""):
        print(f"{cls:14} {c['command']:18} {c['what']}", flush=True)
log.close()
if os.environ.get("KEEP") == "1":
    print(f"every case's message: {W}/errors.txt")
for n in notes:
    print(n)
print(f"{len(cases)} cases ({len(B)} builders, seed {SEED}):", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
