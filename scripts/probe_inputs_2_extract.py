"""Probe 2 cases for `extract`: channel files that do not fit the recording
and CSV recordings in other dialects.
"""
import os

from probe_inputs_common import *  # noqa: F401,F403


# channels.toml edits: (old, new, count) for str.replace; None prepends a line.
CHANNELS_BAD = {
    "index-99": ("index = 7", "index = 99", -1),
    "keyphasor-99": ("channel = 8", "channel = 99", -1),
    "dup-index": ("index = 7", "index = 6", -1),
    "full-scale-0": ("full_scale_v = 10.0", "full_scale_v = 0.0", -1),
    "full-scale-neg": ("full_scale_v = 10.0", "full_scale_v = -10.0", -1),
    "revolutions-0": ("revolutions = 4", "revolutions = 0", -1),
    "revolutions-huge": ("revolutions = 4", "revolutions = 1000000000", -1),
    "threshold-never": ("threshold_v = -5.0", "threshold_v = -50.0", -1),
    "sensitivity-0": ("sensitivity = 7.87", "sensitivity = 0.0", 1),
    "speed-resolution-0": None,
    "unknown-bearing": ('bearing = "right"', 'bearing = "middle"', 1),
}


@builder
def extract_channels_bad(d):
    c, i, rec = extract_case(d, "error", csv=rng.random() < 0.5)
    t = open(i + "/channels.toml").read()
    style = rng.choice(list(CHANNELS_BAD))
    edit = CHANNELS_BAD[style]
    t = t.replace(*edit) if edit else "speed_resolution_hz = 0.0\n" + t
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
