"""What every bad-input probe case is built from (scripts/probe-inputs-2.sh,
scripts/probe-inputs-3.sh): the environment, how plinth is run, the clean
baselines (a simulated run, an imported and an extracted field run, the
clean identification) and the helpers that copy them into a case's
directory. Builders register themselves with `builder`; cases go round the
registered builders in the order they were registered.
"""
import os
import random
import shutil
import struct
import subprocess
import sys


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
