#!/usr/bin/env bash
# plinth diagnose, Monte-Carlo (issue 17), tests/tests/diagnose_bench.rs:
# - the false-alarm rate per run on clean data (rigid skid machine and a
#   three-bearing machine; 3 and 12 digits, 0.5 % noise with *_sd columns,
#   heteroscedastic noise 1 % of each phasor): anything named or an
#   untrusted verdict is a false alarm; with its 95 % Clopper-Pearson
#   upper bound;
# - the detection rate of each effect and combination (probe runout, sensor
#   delay, pedestal cross-coupling, a shared base, a sub-base, a table for a
#   15 % smaller clearance; a base plus runout / delay / cross-coupling;
#   cross-coupling plus delay at two bearings): named right, named wrong,
#   missed.
# Runs are spread over the cores (rayon).
#
#   BENCH_RUNS=25 BENCH_DETECT_RUNS=3 scripts/bench-diagnose.sh [clean|detect]
#   (seeds per clean case, default 25; per detection case, default 3: a run
#   that chooses a base costs minutes under load); BENCH_CASES=TEXT runs
#   only the detection cases whose label holds TEXT (e.g. "skid")
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-1}"
export BENCH_RUNS="${BENCH_RUNS:-25}"
export BENCH_DETECT_RUNS="${BENCH_DETECT_RUNS:-3}"
export BENCH_PART="${1:-}"
cargo test --release -q -p plinth-tests --test diagnose_bench -- --ignored --nocapture bench_rates \
  | grep --line-buffered -E '^(BENCH|  )'
