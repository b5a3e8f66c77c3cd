#!/usr/bin/env bash
# plinth diagnose, Monte-Carlo (issue 17): the false-alarm rate on clean
# runs (rigid skid machine: 0.5 % noise with *_sd columns, and 3 digits)
# and the detection rate of each effect (probe runout, sensor delay,
# pedestal cross-coupling, a shared base, a base plus runout, a sub-base,
# an oil-film table written for a 15 % smaller clearance), all on data made
# by the simulator (tests/tests/diagnose_combined.rs, `bench_rates`).
#
#   BENCH_RUNS=20 scripts/bench-diagnose.sh     (seeds per case; default 20)
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
export BENCH_RUNS="${BENCH_RUNS:-20}"
cargo test --release -p plinth-tests --test diagnose_combined -- --ignored --nocapture bench_rates \
  | grep -E '^(BENCH|false alarm)'
