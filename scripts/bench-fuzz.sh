#!/usr/bin/env bash
# Fuzzes the frame decoder (shared/src/protocol) and the run-directory CSV
# reader (host/src/rundir.rs) for a bounded time each.
#
# With cargo-fuzz and a nightly toolchain: libFuzzer, coverage-guided, from
# the corpus kept in fuzz/corpus/ (new interesting inputs are added there).
# Without them (stable only): the same properties (fuzz/src/lib.rs) on
# corpus files, random mutations of them and random bytes, in a plain loop.
#
# Usage: scripts/bench-fuzz.sh [SECONDS_PER_TARGET]   (default 60)
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
secs=${1:-60}
if cargo +nightly fuzz --version >/dev/null 2>&1; then
  for t in frame_decoder csv_reader; do
    cargo +nightly fuzz run "$t" --features libfuzzer "corpus/$t" -- -max_total_time="$secs"
  done
else
  echo "cargo-fuzz or nightly not available: running the bounded stable loop (cargo install cargo-fuzz for libFuzzer)"
  cargo run --release --bin bounded -- "$secs"
fi
