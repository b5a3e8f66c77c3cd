#!/usr/bin/env bash
# A randomised bad-input probe over every command that reads a file
# (issue 20, item 9): each case takes one valid input of the bundled
# examples, damages it the way a hostile-but-realistic user or a broken
# instrument would (cut short, a byte changed, a field replaced by a hostile
# value, NUL bytes, another separator, a duplicated or missing line, an empty
# file, a directory or a FIFO instead of a file, an over-long line), runs the
# command on it with a time limit and sorts the outcome into one class:
#
#   ok            exit 0 and nothing suspicious in its output
#   clear-error   exit non-zero with `error:` naming a file (with a line or
#                 column where the damage is in a table) or an option
#   unclear-error exit non-zero, but the message names neither
#   panic         `panicked` on stderr
#   abort         killed by a signal (SIGABRT, SIGSEGV, out of memory)
#   hang          still running at the time limit
#   outside-out   a file appeared in the case's directory outside --out
#   garbage       exit 0 but `inf`/`NaN` in what it printed or wrote
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

python3 - "$W" "$EX" "$CASES" "$SEED" <<'PY'
import json, os, random, shutil, sys
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
    ("identify", {"run": W + "/base-run"}, ["identify", "{run}"]),
    ("identify-base", {"run": W + "/base-run"}, ["identify", "{run}", "--json"]),
    ("diagnose", {"run": W + "/base-run", "machine": EX + "/feng-hahn-1997.toml"},
     ["diagnose", "{run}", "--machine", "{machine}"]),
    ("plot", {"run": W + "/base-run"}, ["plot", "{run}", "--out", "{out}"]),
    ("report", {"run": W + "/base-run"}, ["report", "{run}", "--out", "{out}"]),
    ("simulate", {"machine": EX + "/feng-hahn-1997.toml"},
     ["simulate", "{machine}", "--speeds", "5:60:5", "--out", "{out}"]),
    ("signals", {"machine": EX + "/feng-hahn-1997.toml"},
     ["signals", "{machine}", "--rundown", "60:20:2", "--out", "{out}"]),
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

def damage(path, text_like):
    data = bytearray(open(path, "rb").read())
    kind = rng.choice(["cut", "byte", "field", "nul", "semicolon", "dup-line", "drop-line", "empty",
                       "dir", "fifo", "long-line", "field", "field", "utf16", "decimal-comma"])
    if kind == "cut":
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
        return kind
    elif kind == "fifo":
        os.remove(path)
        os.mkfifo(path)
        return kind
    elif kind == "long-line":
        at = rng.randrange(len(data) + 1)
        data[at:at] = b"7" * (3 << 20)
    else:
        kind = "byte"
        if data:
            data[rng.randrange(len(data))] = rng.randrange(256)
    open(path, "wb").write(data)
    return kind

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
                victim = rng.choice(["measurements.csv", "bearings.csv", "base.csv"])
                vp = os.path.join(dst, victim)
                if victim == "base.csv":
                    rows = "".join(f"{s},frame,left;right,1e-8,0,1e-8,0\n" for s in range(5, 61))
                    open(vp, "w").write("speed_hz,base,bearings,y_re,y_im,z_re,z_im\n" + rows)
                kind = damage(vp, True)
                what = f"{victim}: {kind}"
        else:
            shutil.copy(src, dst)
            if key == bad_key:
                kind = damage(dst, not dst.endswith(".wav"))
                what = f"{os.path.basename(dst)}: {kind}"
        files[key] = dst
    argv = [a.format(**files) for a in args] + extra
    cases.append({"dir": d, "command": name, "what": what, "argv": argv, "out": files["out"]})
json.dump(cases, open(os.path.join(W, "cases.json"), "w"))
PY

python3 - "$W" "$PLINTH" "$LIMIT" <<'PY'
import json, os, re, subprocess, sys, signal
W, PLINTH, LIMIT = sys.argv[1], sys.argv[2], float(sys.argv[3])
cases = json.load(open(os.path.join(W, "cases.json")))
counts, notes = {}, []

def listing(d, out):
    seen = set()
    for root, dirs, files in os.walk(d):
        if os.path.abspath(root).startswith(os.path.abspath(out)):
            continue
        for f in files + dirs:
            seen.add(os.path.relpath(os.path.join(root, f), d))
    return seen

for c in cases:
    before = listing(c["dir"], c["out"])
    try:
        p = subprocess.run([PLINTH, "--quiet"] + c["argv"], cwd=c["dir"], capture_output=True,
                           timeout=LIMIT, stdin=subprocess.DEVNULL)
        code, err, out = p.returncode, p.stderr.decode("utf-8", "replace"), p.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        code, err, out = None, "", ""
    after = listing(c["dir"], c["out"])
    new = sorted(x for x in after - before
                 if not (x.startswith("out") or ".incomplete" in x or x.startswith("run")))
    written = ""
    if os.path.isdir(c["out"]):
        for root, _, files in os.walk(c["out"]):
            for f in files:
                if f.endswith((".csv", ".json")):
                    written += open(os.path.join(root, f), errors="replace").read()
    if code is None:
        cls = "hang"
    elif new:
        cls = "outside-out"
    elif "panicked" in err:
        cls = "panic"
    elif code < 0 or code >= 128:
        cls = "abort"
    elif code == 0:
        garbage = re.search(r"(?<![A-Za-z_])(inf|NaN|nan)(?![A-Za-z_])", out + written)
        cls = "garbage" if garbage else "ok"
    else:
        last = [l for l in err.splitlines() if l.startswith("error:")]
        msg = last[-1] if last else err.strip()[-300:]
        names_place = re.search(r"(\.csv|\.toml|\.wav|\.json|raw\.bin|--[a-z]|/)", msg)
        cls = "clear-error" if last and names_place else "unclear-error"
    counts[cls] = counts.get(cls, 0) + 1
    if cls not in ("ok", "clear-error"):
        shown = (err.strip().splitlines() or ["(no message)"])[-1][:300]
        notes.append(f"{cls:14} {c['command']:15} {c['what']}: {shown}")

for n in notes:
    print(n)
print(f"{len(cases)} cases:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
PY
