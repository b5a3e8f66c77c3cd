#!/usr/bin/env bash
# Issue 17's Done-when measured on machines nobody tuned to (docs/unseen.md),
# simulated by ROSS 2.3.0 (scripts/ross_unseen.py), each run through
# `plinth identify` and `plinth diagnose --machine` and tabulated
# (scripts/bench_unseen.py). Machines: unseen-four (default; four bearings,
# an overhung disk: clean runs at 1 % white noise with and without noise
# columns and at 3 digits; a sub-base, a worn bearing's table, pedestal
# cross-coupling, probe runout, three flipped speeds, a shared base plus
# runout) and unseen-overhung (an overhung compressor on two bearings,
# heteroscedastic noise, a coast-down speed grid: clean at 1 %, with
# columns, at 3, 2 and 12 digits; a sub-base, a worn oil film, a wrong
# table scale, cross-coupling, runout, a sensor delay, flips of every
# bearing, one outlier speed, base + runout + delay, two effects at two
# bearings) and unseen-train (a motor-pump train on three bearings, a run-up
# with a skipped band, per-sensor noise: clean-p2/-p2c, clean-d3, clean-dmix
# (2/3/4 digits per bearing), clean-d12, and the effects of its table in
# scripts/ross_unseen.py). $BENCH_DIAGNOSE_PLAIN=1: diagnose without
# --machine.
# usage: scripts/bench-unseen.sh [--machine NAME] [SEEDS [CASE...]]
#   SEEDS default 5 (runs per case; unseen-four's clean-d3 always 4 grids).
#   The run directories are kept in $UNSEEN_RUNS (default
#   target/ross-unseen for unseen-four, target/ross-unseen-NAME otherwise)
#   and made only when missing (ROSS: ~10-30 s per case and speed grid).
#   $BENCH_JOBS workers (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
MACHINE=()
SUFFIX=""
if [ "${1:-}" = "--machine" ]; then
    MACHINE=(--machine "$2")
    [ "$2" = "unseen-four" ] || SUFFIX="-$2"
    shift 2
fi
cargo build --release -q -p plinth
B="${CARGO_TARGET_DIR:-target}/release/plinth"
RUNS="${UNSEEN_RUNS:-${CARGO_TARGET_DIR:-target}/ross-unseen$SUFFIX}"
mkdir -p "$RUNS"
python3 scripts/bench_unseen.py "${MACHINE[@]}" "$B" "$RUNS" "${1:-5}" "${@:2}"
