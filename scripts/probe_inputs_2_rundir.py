"""Probe 2 cases for run directories (identify, diagnose, plot, report):
reordered columns, files that disagree, dialects, odd shapes, options,
and `diagnose --machine` with another machine's file.
"""
import json
import os
import shutil

from probe_inputs_common import *  # noqa: F401,F403
from probe_inputs_2_edits import csv_case, repeat_row


def run_file(expect, commands, file="measurements.csv"):
    """A run-directory case expecting `expect`, its command drawn from
    `commands`, whose `file` the decorated function edits (see `csv_case`)."""
    return csv_case(lambda d: identify_case(d, expect, rng.choice(commands)), file)


# --- run directories
@run_file("neutral", ["identify", "identify", "plot", "report"])
def run_reordered_columns(rows, c):
    order = list(range(len(rows[0])))
    rng.shuffle(order)
    rows = [[x[j] for j in order] for x in rows]
    if rng.random() < 0.6:
        rows = [x + (["comment"] if k == 0 else ["x"]) for k, x in enumerate(rows)]
    c["what"] = "measurements.csv columns shuffled" + (" + unknown column" if rows[0][-1] == "comment" else "")
    return rows


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


@run_file("error", ["identify", "diagnose", "plot", "report"], "bearings.csv")
def run_bearings_disagree(rows, c):
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
        repeat_row(rows, rng.randrange(1, len(rows)), 2, lambda v: str(float(v) * 3))
    else:
        rows = [rows[0]] + rows[1:][::-1]
        c["expect"] = "neutral"
    c["what"] = f"bearings.csv: {style}"
    return rows


@run_file("error", ["identify", "identify", "diagnose", "plot"])
def run_measurements_values(rows, c):
    cmd = c["command"]
    style = rng.choice(["dup-different", "speed-0", "speed-negative", "huge", "case-name",
                        "dead-bearing", "one-speed", "three-speeds", "missing-rows"])
    k = rng.randrange(1, len(rows))
    if style == "dup-different":
        repeat_row(rows, k, 2, lambda v: repr(float(v) * 1.5 + 1e-9))
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
    c["what"] = f"measurements.csv: {style}"
    return rows


@run_file("error", ["identify", "diagnose"])
def run_sd_columns(rows, c):
    style = rng.choice(["two-of-four", "negative", "zero", "nan"])
    names = ["rel_y_sd", "rel_z_sd"] if style == "two-of-four" else ["rel_y_sd", "rel_z_sd", "ped_y_sd", "ped_z_sd"]
    value = {"two-of-four": "1e-9", "negative": "-1e-9", "zero": "0", "nan": "NaN"}[style]
    rows = [x + (names if k == 0 else [value] * len(names)) for k, x in enumerate(rows)]
    c["what"] = f"measurements.csv *_sd columns: {style}"
    return rows


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
