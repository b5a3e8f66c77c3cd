#!/usr/bin/env bash
# A third, independent bad-input probe (issue 20, session 21): hostile but
# realistic cases that scripts/probe-inputs.sh and scripts/probe-inputs-2.sh
# do not make, over every command:
#
#   - field-data oddities: a keyphasor with a second pulse per revolution,
#     a WAV header whose sample rate is not the one sampled at, a channels
#     file listing one input twice (a copied block, two inputs at one place,
#     one input as rel and ped), a second coast-down or a run-up appended to
#     a recording, a stream configuration naming one ADC input twice;
#   - numbers: one cell of one numeric column of every table
#     (measurements.csv, bearings.csv, base.csv, a vector table, a field
#     bearing table, a CSV recording) spelt as a non-finite value the way
#     spreadsheets and C libraries write them (NaN, -nan, Infinity, 1.#INF,
#     #NUM!, ∞ ...); exponents at the ends of the doubles (subnormal, near
#     the largest, 1e-3000, hex, Fortran `1d-3`, a bare `e`) in tables,
#     machine files and options;
#   - names: measurements.csv and bearings.csv from two tools, one with a
#     byte-order mark, CRLF and names padded with spaces or a tab;
#   - directories: a run directory that is a link loop (one or two links),
#     a link to a file, measurements.csv a link to its own directory; --out
#     naming an input directory through another spelling (`run/.`,
#     `run/../run`, a link to it, the machine file's directory);
#   - writers: two commands with --force onto one existing run at once;
#     SIGINT (Ctrl-C) after 0.05-2 s, onto a new --out or with --force over
#     a run: the old run must be intact (or the new one complete, or absent),
#     and what the interrupted command left beside --out must be cleared by
#     the same command run again.
#
# Outcome classes and expectations are those of scripts/probe-inputs-2.sh
# (its header); the builders, baselines and runner are shared with it
# (scripts/probe_inputs_common.py, scripts/probe_inputs_runner.py).
#
# Usage: scripts/probe-inputs-3.sh [CASES [SEED [TIMEOUT_S]]]
#   (defaults 140 cases, seed 1, 20 s per case).
# PLINTH=path/to/plinth overrides the binary; KEEP=1 keeps the work dir;
# PROBE_FLAGS=--classes prints every case's class.
set -euo pipefail

CASES=${1:-140}
SEED=${2:-1}
LIMIT=${3:-20}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PLINTH=${PLINTH:-${CARGO_TARGET_DIR:-$ROOT/target}/release/plinth}
[ -x "$PLINTH" ] || { echo "no plinth binary at $PLINTH: cargo build --release -p plinth" >&2; exit 2; }
W=$(mktemp -d "${TMPDIR:-/tmp}/plinth-probe3.XXXXXX")
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$W"' EXIT
export PLINTH ROOT W CASES SEED LIMIT

exec python3 "$ROOT/scripts/probe_inputs_3.py"
