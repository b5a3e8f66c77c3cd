"""Probe 2 cases for `import`: spreadsheet dialects, tables whose meaning
is off, layouts and bearing tables that disagree, a table of 10^6 rows.
"""
import math

from probe_inputs_common import *  # noqa: F401,F403
from probe_inputs_2_edits import csv_case, repeat_row


def table(expect, file="vector-table.csv"):
    """An import case expecting `expect` whose `file` the decorated function
    edits (see `csv_case`)."""
    return csv_case(lambda d: import_case(d, expect), file)


# --- import: spreadsheet dialects (neutral: same run as the clean table)
@table("neutral")
def import_reordered_extra_columns(rows, c):
    order = list(range(len(rows[0])))
    rng.shuffle(order)
    rows = [[r[j] for j in order] for r in rows]
    extra = rng.choice([["Comment", "Temp (C)"], ["Unnamed: 0"], ["left 45L 1X Amp (old)", "Alarm"]])
    rows = [r + (extra if k == 0 else [rng.choice(["", "ok", "21.5"]) for _ in extra]) for k, r in enumerate(rows)]
    c["what"] = f"table columns shuffled + unknown columns {extra}"
    return rows


@table("neutral")
def import_quoted_numbers(rows, c):
    rows = [r if k == 0 else [f'"{x}"' for x in r] for k, r in enumerate(rows)]
    if rng.random() < 0.5:
        rows[0] = [f'"{x}"' for x in rows[0]]
    c["what"] = "every number quoted (Excel CSV)"
    return rows


@table("neutral")
def import_thousands_separator(rows, c):
    j = rows[0].index("Speed (rpm)")
    style = rng.choice(["quoted-comma", "space", "apostrophe", "unquoted-comma"])
    for r in rows[1:]:
        v = int(float(r[j]))
        if v >= 1000:
            s = f"{v:,}"
            r[j] = {"quoted-comma": f'"{s}"', "space": s.replace(",", " "),
                    "apostrophe": s.replace(",", "'"), "unquoted-comma": s}[style]
    if style != "quoted-comma":
        c["expect"] = "error"
    c["what"] = f"speeds with thousands separators ({style})"
    return rows


@table("neutral")
def import_trailing_empty_columns(rows, c):
    n = rng.choice([1, 3])
    rows = [r + [""] * n for r in rows]
    c["what"] = f"{n} trailing empty columns on every line"
    return rows


@table("error")
def import_na_cell(rows, c):
    k = rng.randrange(1, len(rows))
    j = rng.randrange(1, len(rows[0]))
    rows[k][j] = rng.choice(["#N/A", "#VALUE!", "#DIV/0!", "N/A", "-", "---"])
    c["what"] = f"{rows[k][j]} at line {k + 1} column {rows[0][j]!r}"
    c["names_line"] = True
    return rows


@table("neutral")
def import_trailing_spaces(rows, c):
    head = rng.random() < 0.5
    rows = [[x + " " if (k > 0 or head) else x for x in r] for k, r in enumerate(rows)]
    c["what"] = "trailing spaces in every cell" + (" and the header" if head else "")
    return rows


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


@table("error")
def import_units_row_or_comments(rows, c):
    style = rng.choice(["units-row", "comment-lines", "title-line"])
    if style == "units-row":
        rows.insert(1, ["", "rpm"] + ["um pp" if "Amp" in h else "deg" for h in rows[0][2:]])
    elif style == "comment-lines":
        rows = [["# Exported by ADRE 408"], ["# Machine: BFP-A"]] + rows
    else:
        rows = [["Run-down 3 May 2025"]] + rows
    c["what"] = f"table with {style}"
    c["names_line"] = True
    return rows


@table("warn")
def import_phase_radians(rows, c):
    for j in table_header_index(rows, lambda h: "Phase" in h):
        for r in rows[1:]:
            r[j] = f"{math.radians(float(r[j])):.4f}"
    c["what"] = "phases written in radians where the layout says degrees"
    return rows


@table("neutral")
def import_phase_wrapped(rows, c):
    style = rng.choice(["+360", "+720", "-360"])
    add = {"+360": 360, "+720": 720, "-360": -360}[style]
    for j in table_header_index(rows, lambda h: "Phase" in h):
        for r in rows[1:]:
            r[j] = f"{float(r[j]) + add:g}"
    c["what"] = f"phases {style} (same angle)"
    c["compare"] = ("phasors", "measurements.csv", W + "/base-import/measurements.csv")
    return rows


@table("warn")
def import_speed_repeated(rows, c):
    k = rng.randrange(2, len(rows) - 1)
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h))
    dup = repeat_row(rows, k, j, lambda v: f"{float(v) * 1.7:.3g}")
    c["what"] = f"speed {dup[1]} rpm twice with different amplitudes"
    return rows


@table("neutral")
def import_speed_shuffled(rows, c):
    body = rows[1:]
    rng.shuffle(body)
    c["what"] = "rows in random order (speeds not monotonic)"
    c["compare"] = ("sorted", "measurements.csv", W + "/base-import/measurements.csv")
    return [rows[0]] + body


@table("error")
def import_speed_zero_negative(rows, c):
    k = rng.randrange(1, len(rows))
    rows[k][1] = rng.choice(["0", "-0", "-1500", "1e-300", "-4500"])
    c["what"] = f"speed {rows[k][1]} rpm at line {k + 1}"
    c["names_line"] = True
    if rows[k][1] in ("0", "-0", "1e-300"):
        c["expect"] = "warn"
    return rows


@table("error")
def import_huge_exponent(rows, c):
    k = rng.randrange(1, len(rows))
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h or "Phase" in h))
    rows[k][j] = rng.choice(["1e308", "9e307", "1.0E+300", "1e-308", "4.9e-324"])
    if "Phase" in rows[0][j] or rows[k][j] in ("1e-308", "4.9e-324"):
        c["expect"] = "any"
    c["what"] = f"{rows[k][j]} at line {k + 1} column {rows[0][j]!r}"
    c["names_line"] = c["expect"] == "error"
    return rows


@table("error")
def import_unit_in_cell(rows, c):
    k = rng.randrange(1, len(rows))
    j = rng.choice(table_header_index(rows, lambda h: "Amp" in h))
    rows[k][j] = rows[k][j] + rng.choice([" um", "um", " µm pp", "mm/s"])
    c["what"] = f"a unit inside the cell: {rows[k][j]!r} at line {k + 1}"
    c["names_line"] = True
    return rows


@table("any")
def import_blank_row(rows, c):
    k = rng.randrange(2, len(rows))
    rows.insert(k, [""] * rng.choice([len(rows[0]), 1]))
    c["what"] = f"an empty row at line {k + 1}"
    return rows


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


@table("error", "bearings.csv")
def import_bearings_mismatch(rows, c):
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
        repeat_row(rows, rng.randrange(1, len(rows)), 2, lambda v: str(float(v) * 2))
    else:
        rows += [[r[0], "middle"] + r[2:] for r in rows[1:] if r[1] == "left"]
        c["expect"] = "any"
    c["what"] = f"bearings.csv: {style}"
    return rows


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
