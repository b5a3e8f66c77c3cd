#!/usr/bin/env bash
# A randomised bad-input probe over every command that reads a file
# (issue 20, item 9): each case takes one valid input of the bundled
# examples, damages it the way a hostile-but-realistic user or a broken
# instrument would (cut short, a byte changed, a field replaced by a hostile
# value, NUL bytes, another separator, a duplicated or missing line, an empty
# file, a directory or a FIFO instead of a file, an over-long line), runs the
# command on it with a time limit and sorts the outcome into one class.
# Session 19 added: a WAV header that lies (channels, sizes, rate, bits), a
# byte-order mark with CRLF line ends, a whole numeric column replaced by
# NaN/inf/1e999/0/negative (every table kind, a CSV recording too), TOML
# with duplicate keys, huge arrays or deep nesting, symbolic links as
# inputs (to a copy, dangling, a loop, /dev/zero) and as --out, --out equal
# to an input's directory, very long file names, unknown extra files in a
# run directory, and commands killed (SIGKILL) mid-run then run again.
#
#   ok            exit 0 and nothing suspicious in its output
#   clear-error   exit non-zero with `error:` naming a file (with a line or
#                 column where the damage is in a table) or an option
#   unclear-error exit non-zero, but the message names neither
#   panic         `panicked` on stderr
#   abort         killed by a signal (SIGABRT, SIGSEGV, out of memory)
#   hang          still running at the time limit
#   outside-out   a file appeared in the case's directory outside --out
#   garbage       exit 0 but `inf`/`NaN` in what it printed or wrote, or a
#                 whole column of NaN/inf/1e999 taken without a warning
#   data-loss     a file that existed before the command (outside --out) was
#                 changed or removed
#
# Usage: scripts/probe-inputs.sh [CASES [SEED [TIMEOUT_S]]]
#   (defaults 150 cases, seed 1, 20 s per case; a few minutes in all).
# PLINTH=path/to/plinth overrides the binary (default target/release/plinth).
# Cases whose class is not ok or clear-error are listed with their command
# and message; the work directory is kept when KEEP=1.
set -euo pipefail

CASES=${1:-150}
SEED=${2:-1}
LIMIT=${3:-20}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PLINTH=${PLINTH:-${CARGO_TARGET_DIR:-$ROOT/target}/release/plinth}
[ -x "$PLINTH" ] || { echo "no plinth binary at $PLINTH: cargo build --release -p plinth" >&2; exit 2; }
W=$(mktemp -d "${TMPDIR:-/tmp}/plinth-probe.XXXXXX")
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$W"' EXIT
EX=$ROOT/examples

# Valid inputs every case starts from.
"$PLINTH" --quiet simulate "$EX/feng-hahn-1997.toml" --speeds 5:60:1 --out "$W/base-run" >/dev/null
# The example recording as a CSV recording (`time_s`, then volts).
python3 - "$EX/field/recording.wav" "$W/recording.csv" <<'PY'
import struct, sys
b = open(sys.argv[1], "rb").read()
ch, rate, bits = struct.unpack("<H", b[22:24])[0], struct.unpack("<I", b[24:28])[0], struct.unpack("<H", b[34:36])[0]
at = b.index(b"data") + 8
w = bits // 8
rows = ["time_s," + ",".join(f"c{i}" for i in range(ch))]
for k, i in enumerate(range(at, len(b) - ch * w + 1, ch * w)):
    v = [int.from_bytes(b[i + j * w:i + (j + 1) * w], "little", signed=True) * 10.0 / 2 ** (bits - 1) for j in range(ch)]
    rows.append(f"{k / rate:.9f}," + ",".join(f"{x:.6f}" for x in v))
open(sys.argv[2], "w").write("\n".join(rows) + "\n")
PY

python3 - "$W" "$EX" "$CASES" "$SEED" <<'PY'
import json, os, random, shutil, struct, sys
W, EX, CASES, SEED = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
rng = random.Random(SEED)
HOSTILE = ["", "nan", "inf", "-inf", "-1", "0", "1e300", "-1e300", "1e-320", "../../x", "a/b",
           "a;b", "1,234", "\"", "x" * 5000, "\t", "0x10", "1e", "٣", "DE/NDE", " left", "left "]
# Each command: (name, {input key: example file}, argument template).
# {out} is the case's output directory, other keys the damaged files.
F = EX + "/field/"
COMMANDS = [
    ("import", {"table": F + "vector-table.csv", "layout": F + "layout.toml", "bearings": F + "bearings.csv"},
     ["import", "{table}", "--layout", "{layout}", "--bearings", "{bearings}", "--out", "{out}", "--plots"]),
    ("extract", {"recording": F + "recording.wav", "channels": F + "channels.toml", "bearings": F + "bearings.csv"},
     ["extract", "{recording}", "--channels", "{channels}", "--bearings", "{bearings}", "--out", "{out}"]),
    ("extract-csv", {"recording": W + "/recording.csv", "channels": F + "channels.toml", "bearings": F + "bearings.csv"},
     ["extract", "{recording}", "--channels", "{channels}", "--bearings", "{bearings}", "--out", "{out}"]),
    ("identify", {"run": W + "/base-run"}, ["identify", "{run}"]),
    ("identify-base", {"run": W + "/base-run"}, ["identify", "{run}", "--json"]),
    ("diagnose", {"run": W + "/base-run", "machine": EX + "/feng-hahn-1997.toml"},
     ["diagnose", "{run}", "--machine", "{machine}"]),
    ("plot", {"run": W + "/base-run"}, ["plot", "{run}", "--out", "{out}"]),
    ("report", {"run": W + "/base-run"}, ["report", "{run}", "--out", "{out}"]),
    ("simulate", {"machine": EX + "/feng-hahn-1997.toml"},
     ["simulate", "{machine}", "--speeds", "5:60:5", "--out", "{out}"]),
    ("signals", {"machine": EX + "/feng-hahn-1997.toml"},
     ["signals", "{machine}", "--rundown", "60:50:5", "--out", "{out}"]),
    ("accuracy", {"machine": EX + "/feng-hahn-1997.toml"},
     ["accuracy", "{machine}", "--draws", "4", "--speeds", "5:60:5"]),
    ("stream-offline", {"raw": None, "config": None},
     ["stream", "--offline", "--config", "{config}", "--out", "{out}"]),
]
BAD_OPTIONS = [("accuracy", ["--draws", "1000000000"]), ("accuracy", ["--noise", "1e10"]),
               ("accuracy", ["--speeds", "5"]), ("simulate", ["--speeds", "0:1e9:1e-3"]),
               ("signals", ["--rate", "1e12"]), ("signals", ["--grid-step", "1e-12"]),
               ("identify", ["--estimator", "ols", "--unmeasured-base"]),
               ("plot", ["--out", "/"]), ("import", ["--slow-roll", "9:1"])]

def stream_config(d):
    s = 'bearings = "bearings.csv"\n'
    for b, bearing in enumerate(["left", "right"]):
        for q, quantity in enumerate(["rel_y", "rel_z", "ped_y", "ped_z"]):
            s += f'\n[[channels]]\nadc = {4*b+q}\nbearing = "{bearing}"\nquantity = "{quantity}"\nsensor = "proximity"\nsensitivity = 7870.0\n'
    open(os.path.join(d, "stream.toml"), "w").write(s)

NUMERIC_HOSTILE = ["nan", "NaN", "inf", "-inf", "1e999", "-1e999", "0", "-0", "-5", "1e-400"]
NON_FINITE = {"nan", "NaN", "inf", "-inf", "1e999", "-1e999"}
OLD_KINDS = ["cut", "byte", "field", "nul", "semicolon", "dup-line", "drop-line", "empty",
             "dir", "fifo", "long-line", "field", "field", "utf16", "decimal-comma"]
NEW_KINDS = ["wav-header", "bom-crlf", "column", "column", "column", "toml-dup", "toml-huge-array",
             "toml-deep", "symlink", "long-name"]

def wav_header(data):
    """A WAV header that lies: returns what it says now."""
    fmt = data.index(b"fmt ") + 8
    size_at = data.index(b"data") + 4
    lie = rng.choice(["channels", "channels-65535", "data-size", "rate-0", "rate-huge", "bits-12", "fmt-size"])
    if lie == "channels":
        ch = struct.unpack("<H", data[fmt + 2:fmt + 4])[0]
        data[fmt + 2:fmt + 4] = struct.pack("<H", ch * 2)
        bits = struct.unpack("<H", data[fmt + 14:fmt + 16])[0]
        data[fmt + 12:fmt + 14] = struct.pack("<H", ch * 2 * bits // 8)
    elif lie == "channels-65535":
        data[fmt + 2:fmt + 4] = struct.pack("<H", 65535)
        data[fmt + 12:fmt + 14] = struct.pack("<H", (65535 * 3) & 0xFFFF)
    elif lie == "data-size":
        data[size_at:size_at + 4] = struct.pack("<I", 0x7FFFFFF0)
    elif lie == "rate-0":
        data[fmt + 4:fmt + 8] = struct.pack("<I", 0)
    elif lie == "rate-huge":
        data[fmt + 4:fmt + 8] = struct.pack("<I", 4_000_000_000)
    elif lie == "bits-12":
        data[fmt + 14:fmt + 16] = struct.pack("<H", 12)
    else:
        data[fmt - 4:fmt] = struct.pack("<I", 0xFFFFFF00)
    return "wav-header " + lie

def replace_column(data):
    """One numeric column of every data row replaced by one hostile value."""
    text = data.decode("utf-8", "replace")
    lines = text.split("\n")
    width = len(lines[0].split(","))
    j = rng.randrange(width)
    value = rng.choice(NUMERIC_HOSTILE)
    for i in range(1, len(lines)):
        parts = lines[i].split(",")
        if len(parts) == width:
            try:
                float(parts[j])
            except ValueError:
                continue
            parts[j] = value
            lines[i] = ",".join(parts)
    return bytearray("\n".join(lines).encode()), f"column {lines[0].split(',')[j]!r} = {value}", value

def damage(path, text_like, allow_new=True):
    data = bytearray(open(path, "rb").read())
    kind = rng.choice(OLD_KINDS + (NEW_KINDS * 2 if allow_new else []))
    is_csv, is_toml, is_wav = path.endswith(".csv"), path.endswith(".toml"), path.endswith(".wav")
    if kind == "wav-header" and is_wav:
        kind = wav_header(data)
    elif kind == "bom-crlf" and text_like:
        data = bytearray(b"\xef\xbb\xbf" + bytes(data).replace(b"\n", b"\r\n"))
    elif kind == "column" and is_csv:
        data, kind, value = replace_column(data)
        open(path, "wb").write(data)
        return kind, value in NON_FINITE
    elif kind == "toml-dup" and is_toml:
        lines = data.split(b"\n")
        keyed = [i for i, l in enumerate(lines) if b"=" in l and not l.lstrip().startswith(b"#")]
        i = rng.choice(keyed)
        lines.insert(i + 1, lines[i])
        data = bytearray(b"\n".join(lines))
    elif kind == "toml-huge-array" and is_toml:
        data = bytearray(b"huge = [" + b"0," * 1_000_000 + b"0]\n") + data
    elif kind == "toml-deep" and is_toml:
        depth = rng.choice([1000, 100_000])
        data = bytearray(b"deep = " + b"[" * depth + b"]" * depth + b"\n") + data
    elif kind == "symlink":
        target = rng.choice(["copy", "dangling", "loop", "/dev/zero"])
        keep = path + ".orig"
        os.rename(path, keep)
        if target == "copy":
            os.symlink(keep, path)
        elif target == "dangling":
            os.symlink(path + ".missing", path)
        elif target == "loop":
            os.symlink(path, path)
        else:
            os.symlink("/dev/zero", path)
        return f"symlink to {target}", False
    elif kind == "long-name":
        return "long-name", False  # renamed by the caller
    elif kind in NEW_KINDS:
        kind = "byte"
        if data:
            data[rng.randrange(len(data))] = rng.randrange(256)
    elif kind == "cut":
        data = data[: rng.randrange(0, max(1, len(data)))]
    elif kind == "byte" and data:
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(len(data))] = rng.randrange(256)
    elif kind == "field" and text_like:
        lines = data.decode("utf-8", "replace").split("\n")
        i = rng.randrange(len(lines))
        sep = "," if "," in lines[i] else "="
        parts = lines[i].split(sep)
        j = rng.randrange(len(parts))
        parts[j] = (" " if sep == "=" else "") + rng.choice(HOSTILE)
        lines[i] = sep.join(parts)
        data = bytearray("\n".join(lines).encode())
    elif kind == "nul":
        at = rng.randrange(len(data) + 1)
        data[at:at] = b"\0" * rng.choice([1, 64, 1 << 20])
    elif kind == "semicolon" and text_like:
        data = data.replace(b",", b";")
    elif kind == "decimal-comma" and text_like:
        data = data.replace(b",", b";").replace(b".", b",")
    elif kind == "utf16" and text_like:
        data = bytearray(b"\xff\xfe" + data.decode("utf-8", "replace").encode("utf-16-le"))
    elif kind in ("dup-line", "drop-line") and text_like:
        lines = data.split(b"\n")
        i = rng.randrange(len(lines))
        if kind == "dup-line":
            lines.insert(i, lines[i])
        else:
            del lines[i]
        data = bytearray(b"\n".join(lines))
    elif kind == "empty":
        data = bytearray()
    elif kind == "dir":
        os.remove(path)
        os.mkdir(path)
        return kind, False
    elif kind == "fifo":
        os.remove(path)
        os.mkfifo(path)
        return kind, False
    elif kind == "long-line":
        at = rng.randrange(len(data) + 1)
        data[at:at] = b"7" * (3 << 20)
    else:
        kind = "byte"
        if data:
            data[rng.randrange(len(data))] = rng.randrange(256)
    open(path, "wb").write(data)
    return kind, False

def extra_files(run):
    """Unknown files a user leaves in a run directory."""
    open(os.path.join(run, "notes.txt"), "w").write("run-down of 3 May, by hand\n")
    shutil.copy(os.path.join(run, "measurements.csv"), os.path.join(run, "measurements.csv~"))
    open(os.path.join(run, ".DS_Store"), "wb").write(bytes(range(256)))
    os.mkdir(os.path.join(run, "old"))
    shutil.copy(os.path.join(run, "measurements.csv"), os.path.join(run, "old", "measurements.csv"))

# Whole-case variations of --out and of the run (not of one file).
OUT_KINDS = ["out-symlink", "out-is-input-dir", "out-long-name", "interrupt", "interrupt"]

cases = []
for n in range(CASES):
    d = os.path.join(W, f"case{n:04d}")
    os.mkdir(d)
    if rng.random() < 0.12:
        name, extra = rng.choice(BAD_OPTIONS)
        cmd = next(c for c in COMMANDS if c[0] == name)
        _, inputs, args = cmd
        what = "option " + " ".join(extra)
        bad_key = None
    else:
        name, inputs, args = rng.choice(COMMANDS)
        extra = []
        bad_key = rng.choice([k for k in inputs])
        what = None
    files = {"out": os.path.join(d, "out")}
    for key, src in inputs.items():
        if name == "stream-offline":
            run = os.path.join(d, "run")
            shutil.copytree(W + "/base-run", run)
            stream_config(run)
            raw = bytes(rng.randrange(256) for _ in range(rng.choice([0, 17, 4096])))
            open(os.path.join(run, "raw.bin"), "wb").write(raw)
            files = {"out": run, "config": os.path.join(run, "stream.toml"), "raw": os.path.join(run, "raw.bin")}
            what = f"raw log of {len(raw)} random bytes"
            break
        dst = os.path.join(d, os.path.basename(src))
        if os.path.isdir(src):
            shutil.copytree(src, dst)
            if key == bad_key:
                if rng.random() < 0.15:
                    extra_files(dst)
                    what = "run directory with unknown extra files"
                else:
                    victim = rng.choice(["measurements.csv", "bearings.csv", "base.csv"])
                    vp = os.path.join(dst, victim)
                    if victim == "base.csv":
                        # A measured base that does not move: valid for the simulated run.
                        rows = "".join(f"{s},frame,left;right,0,0,0,0\n" for s in range(5, 61))
                        open(vp, "w").write("speed_hz,base,bearings,y_re,y_im,z_re,z_im\n" + rows)
                    kind, non_finite = damage(vp, True)
                    if kind == "long-name":  # the file renamed: the run lacks it
                        os.rename(vp, os.path.join(dst, victim[:-4] + "-" + "x" * (245 - len(victim)) + ".csv"))
                    what = f"{victim}: {kind}"
        else:
            shutil.copy(src, dst)
            if key == bad_key:
                kind, non_finite = damage(dst, not dst.endswith(".wav"))
                if kind == "long-name":
                    stem, ext = os.path.splitext(os.path.basename(dst))
                    longer = os.path.join(d, stem + "-" + "x" * (250 - len(stem) - len(ext)) + ext)
                    os.rename(dst, longer)
                    dst = longer
                what = f"{os.path.basename(dst)[:40]}: {kind}"
        files[key] = dst
    out_kind = None
    if what is not None and rng.random() < 0.2 and name not in ("stream-offline",):
        # A whole-case variation instead of a damaged file: inputs are valid.
        out_kind = rng.choice(OUT_KINDS)
        if "{out}" not in args and out_kind != "interrupt":
            out_kind = "interrupt"
        what = out_kind
        non_finite = False
        for key, src in inputs.items():  # undo the damage: fresh copies
            dst = os.path.join(d, "valid", os.path.basename(src))
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            (shutil.copytree if os.path.isdir(src) else shutil.copy)(src, dst)
            files[key] = dst
        if out_kind == "out-symlink":
            os.mkdir(os.path.join(d, "elsewhere"))
            os.symlink(os.path.join(d, "elsewhere"), files["out"])
        elif out_kind == "out-is-input-dir":
            files["out"] = os.path.join(d, "valid")
        elif out_kind == "out-long-name":
            files["out"] = os.path.join(d, "out-" + "y" * 300)
    elif what is None or "column" not in (what or ""):
        non_finite = False
    argv = [a.format(**files) for a in args] + extra
    cases.append({"dir": d, "command": name, "what": what, "argv": argv, "out": files["out"],
                  "kind": out_kind, "non_finite": bool(non_finite)})
json.dump(cases, open(os.path.join(W, "cases.json"), "w"))
PY

python3 - "$W" "$PLINTH" "$LIMIT" <<'PY'
import hashlib, json, os, random, re, subprocess, sys, signal, time
W, PLINTH, LIMIT = sys.argv[1], sys.argv[2], float(sys.argv[3])
cases = json.load(open(os.path.join(W, "cases.json")))
counts, notes = {}, []
rng = random.Random(len(cases))

def contents(d, out):
    """Every regular file and link under `d` but outside `out`: path -> digest."""
    seen = {}
    for root, dirs, files in os.walk(d):
        if os.path.abspath(root).startswith(os.path.abspath(out)):
            continue
        for f in files + dirs:
            p = os.path.join(root, f)
            if os.path.abspath(p).startswith(os.path.abspath(out)):
                continue
            if os.path.islink(p):
                seen[p] = "link " + os.readlink(p)
            elif os.path.isfile(p):
                seen[p] = hashlib.sha1(open(p, "rb").read()).hexdigest()
    return seen

def killed_midway(argv, cwd):
    """Starts the command, SIGKILLs it after a random moment."""
    p = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         stdin=subprocess.DEVNULL)
    try:
        p.wait(timeout=rng.uniform(0.02, 1.5))
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()

def listing(d, out):
    seen = set()
    for root, dirs, files in os.walk(d):
        if os.path.abspath(root).startswith(os.path.abspath(out)):
            continue
        for f in files + dirs:
            seen.add(os.path.relpath(os.path.join(root, f), d))
    return seen

for c in cases:
    if c["kind"] == "interrupt":
        killed_midway([PLINTH, "--quiet"] + c["argv"], c["dir"])
    before = listing(c["dir"], c["out"])
    # --out that is an input's directory: everything there must survive.
    guard = os.path.join(c["dir"], "-") if c["kind"] == "out-is-input-dir" else c["out"]
    kept = contents(c["dir"], guard) if c["command"] != "stream-offline" else {}
    # What a killed Plinth left (its lock, its staging directory) is the
    # next run's to clear, not the user's data.
    kept = {p: h for p, h in kept.items() if ".plinth-" not in p}
    try:
        p = subprocess.run([PLINTH, "--quiet"] + c["argv"], cwd=c["dir"], capture_output=True,
                           timeout=LIMIT, stdin=subprocess.DEVNULL)
        code, err, out = p.returncode, p.stderr.decode("utf-8", "replace"), p.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        code, err, out = None, "", ""
    after = listing(c["dir"], c["out"])
    new = sorted(x for x in after - before
                 if not (x.startswith("out") or ".incomplete" in x or x.startswith("run")))
    if c["kind"] == "interrupt":
        # Whatever the killed run left must be gone after the rerun.
        new += sorted(x for x in after if x.startswith(".") and "plinth" in x)
    now = contents(c["dir"], guard) if kept else {}
    lost = sorted(os.path.relpath(p, c["dir"]) for p, h in kept.items() if now.get(p) != h)
    written = ""
    if os.path.isdir(c["out"]):
        for root, _, files in os.walk(c["out"]):
            for f in files:
                if f.endswith((".csv", ".json")):
                    written += open(os.path.join(root, f), errors="replace").read()
    if code is None:
        cls = "hang"
    elif lost:
        cls = "data-loss"
        err += "\nchanged or removed: " + ", ".join(lost[:5])
    elif new:
        cls = "outside-out"
    elif "panicked" in err:
        cls = "panic"
    elif code < 0 or code >= 128:
        cls = "abort"
    elif code == 0:
        garbage = re.search(r"(?<![A-Za-z_])(inf|NaN|nan)(?![A-Za-z_])", out + written)
        # A whole column of non-finite values taken without a word.
        silent = c["non_finite"] and "warning" not in err
        cls = "garbage" if garbage or silent else "ok"
    else:
        last = [l for l in err.splitlines() if l.startswith("error:")]
        msg = last[-1] if last else err.strip()[-300:]
        names_place = re.search(r"(\.csv|\.toml|\.wav|\.json|raw\.bin|--[a-z]|/)", msg)
        cls = "clear-error" if last and names_place else "unclear-error"
    counts[cls] = counts.get(cls, 0) + 1
    if cls not in ("ok", "clear-error"):
        shown = (err.strip().splitlines() or ["(no message)"])[-1][:300]
        notes.append(f"{cls:14} {c['command']:15} {c['what']}: {shown}")
    if "--classes" in os.environ.get("PROBE_FLAGS", ""):
        print(f"{cls:14} {c['command']:15} {c['what']}")

for n in notes:
    print(n)
print(f"{len(cases)} cases:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
PY
