#!/usr/bin/env bash
# Issue 17's Done-when measured on a machine nobody tuned to (docs/unseen.md):
# a four-bearing machine with an overhung disk simulated by ROSS 2.3.0
# (scripts/ross_unseen.py: clean runs at 1 % white noise with and without
# noise columns and at 3 digits; a sub-base, a worn bearing's table,
# pedestal cross-coupling, probe runout, three flipped speeds, a shared base
# plus runout), each run through `plinth identify` and
# `plinth diagnose --machine` and tabulated (scripts/bench_unseen.py).
# usage: scripts/bench-unseen.sh [SEEDS [CASE...]]
#   SEEDS default 5 (runs per case; clean-d3 always 4 grids). The run
#   directories are kept in $UNSEEN_RUNS (default target/ross-unseen) and
#   made only when missing (ROSS: ~10 s per case). $BENCH_JOBS workers
#   (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p plinth
B="${CARGO_TARGET_DIR:-target}/release/plinth"
RUNS="${UNSEEN_RUNS:-${CARGO_TARGET_DIR:-target}/ross-unseen}"
mkdir -p "$RUNS"
python3 scripts/bench_unseen.py "$B" "$RUNS" "${1:-5}" "${@:2}"
