#!/usr/bin/env bash
# A second, independent bad-input probe (issue 20, session 20): hostile but
# realistic inputs that scripts/probe-inputs.sh does not make. Where the
# first probe damages bytes at random, this one builds each case the way a
# field engineer's messy file or an attacker's input looks:
#
#   - spreadsheet exports: columns in another order plus unknown columns,
#     quoted numbers, thousands separators, trailing empty columns, `#N/A`,
#     trailing spaces, a units row, comment lines, no final newline, CRLF +
#     BOM all at once;
#   - tables whose meaning is off: phases in radians, phases past 360 or
#     negative, speeds repeated with other values, a speed of 0 or below,
#     rows shuffled, a huge exponent, a unit written into the cell;
#   - run directories whose files disagree: truth.json or bearings.csv
#     naming other bearings, bearing names differing in case, a dead
#     bearing, `*_sd` columns incomplete or negative, one speed only;
#   - machine files with a negative length, a zero diameter, NaN, a bearing
#     or disk outside the shaft, no bearing, two bearings of one name, an
#     unknown key, 10⁹ elements;
#   - channel files naming channels the recording does not have, a zero
#     full scale, a keyphasor threshold never crossed;
#   - options: --speeds inverted / step 0 / 10¹⁰ points, --rundown rates of
#     0 or 10⁻⁹ Hz/s, --draws 0, stream --window 10¹², --port a regular file;
#   - --out an existing file, an input file, a directory inside an input
#     directory, the parent of the inputs, two commands on one --out at the
#     same time; 10⁶-row tables against PLINTH_MEMORY_MB.
#
# Outcome classes are those of scripts/probe-inputs.sh, plus what a case
# expects: a case marked `neutral` (a harmless dialect: reordered columns,
# quotes, CRLF) must give the same result as the clean input or a clear
# error; a case marked `warn` must not pass with exit 0 and no warning; a
# case marked `error` must not pass at all. Breaking these is `garbage`.
#
# Usage: scripts/probe-inputs-2.sh [CASES [SEED [TIMEOUT_S]]]
#   (defaults 220 cases, seed 1, 20 s per case).
# PLINTH=path/to/plinth overrides the binary; KEEP=1 keeps the work dir;
# PROBE_FLAGS=--classes prints every case's class.
set -euo pipefail

CASES=${1:-220}
SEED=${2:-1}
LIMIT=${3:-20}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PLINTH=${PLINTH:-${CARGO_TARGET_DIR:-$ROOT/target}/release/plinth}
[ -x "$PLINTH" ] || { echo "no plinth binary at $PLINTH: cargo build --release -p plinth" >&2; exit 2; }
W=$(mktemp -d "${TMPDIR:-/tmp}/plinth-probe2.XXXXXX")
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$W"' EXIT
export PLINTH ROOT W CASES SEED LIMIT

exec python3 "$ROOT/scripts/probe_inputs_2.py"
