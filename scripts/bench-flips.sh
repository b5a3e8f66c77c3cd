#!/usr/bin/env bash
# Monte-Carlo of identify's keyphasor-flip detection (issue 17 item 2): the
# rate of clean runs (the clean cases of scripts/bench-trust.sh) on which a
# flip is named, with its one-sided 95 % upper bound (Clopper-Pearson), and
# the rate at which flipped speeds of `mid` (3 random, 2 and 3 adjacent, the
# pair next to its resonance) are listed exactly, and the same on three
# machines not tuned to (ROSS c and d, three pedestals on a frame; every
# bearing flipped in turn) (scripts/bench_flips.py).
# Runs go in parallel over $BENCH_JOBS workers (default: every CPU).
# usage: scripts/bench-flips.sh [RUNS_PER_CLEAN_CASE [CASE_FILTER]]
#   default 200 per clean case (18 cases) and 40 per detection case.
#   CASE_FILTER: only the clean cases whose name contains it, no detections.
#   BENCH_SECTIONS=other (or clean, detect; comma-separated): those parts only.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p plinth
B="${CARGO_TARGET_DIR:-target}/release/plinth"
python3 scripts/bench_flips.py "$B" "${1:-200}" "${2:-}"
