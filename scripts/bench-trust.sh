#!/usr/bin/env bash
# Monte-Carlo of identify's trust rules (issue 17): the false-alarm rate per
# run on clean data (digits 2/3/12, white noise 0.3/1/3 %, heteroscedastic
# noise, noise columns, noise at 3 digits; the undamped paper machine and a
# three-bearing machine) of every rule that marks a pedestal untrusted, lists
# outlier speeds or exits 2, and the detection rates of the faults they are
# for (scripts/bench_trust.py). Prints a table: case, runs, flagged % by rule,
# the run-level rate with its one-sided 95 % upper bound (Clopper-Pearson).
# Runs go in parallel over $BENCH_JOBS workers (default: every CPU).
# usage: scripts/bench-trust.sh [RUNS_PER_CASE [CASE_FILTER]]
#   RUNS_PER_CASE default 100 (heteroscedastic cases at least 200; each
#   digit run on its own speed grid): ~2 000 runs, ~5 min on 2 cores.
#   CASE_FILTER: only the false-alarm cases whose name contains it, e.g.
#   scripts/bench-trust.sh 300 "paper-undamped hetero"
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p plinth
B="${CARGO_TARGET_DIR:-target}/release/plinth"
python3 scripts/bench_trust.py "$B" "${1:-100}" "${2:-}"
