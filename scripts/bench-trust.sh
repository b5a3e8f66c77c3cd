#!/usr/bin/env bash
# Monte-Carlo of identify's trust rules (issue 17): the false-alarm rate per
# run on clean data (digits 2/3/12, white noise 0.3/1/3 %, heteroscedastic
# noise, noise columns, noise at 3 digits; the undamped paper machine and a
# three-bearing machine) of every rule that marks a pedestal untrusted, lists
# outlier speeds or exits 2, and the detection rates of the faults they are
# for (scripts/bench_trust.py). Prints a table: case, runs, flagged % by rule.
# usage: scripts/bench-trust.sh [RUNS_PER_NOISY_CASE]   (default 200)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p plinth
B="${CARGO_TARGET_DIR:-target}/release/plinth"
python3 scripts/bench_trust.py "$B" "${1:-200}"
