#!/usr/bin/env bash
# Fuzzes the frame decoder (shared/src/protocol) and the run-directory CSV
# reader (host/src/rundir/read.rs) for a bounded time each.
#
# With cargo-fuzz and a nightly toolchain: libFuzzer, coverage-guided, seeded
# from the corpus kept in fuzz/corpus/TARGET (read only); the inputs it finds
# go to a temporary directory (their count is printed; copy the few worth
# keeping into fuzz/corpus/TARGET). A crash is saved under
# fuzz/artifacts/TARGET and fails the script.
# Without them (stable only): the same properties (fuzz/src/lib.rs) on
# corpus files, random mutations of them and random bytes, in a plain loop.
#
# Usage: scripts/bench-fuzz.sh [SECONDS_PER_TARGET]   (default 60)
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
secs=${1:-60}
if cargo +nightly fuzz --version >/dev/null 2>&1; then
  echo "libFuzzer (cargo +nightly fuzz), ${secs} s per target"
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  for t in frame_decoder csv_reader; do
    mkdir -p "$work/$t"
    cargo +nightly fuzz run "$t" --features libfuzzer "$work/$t" "corpus/$t" -- \
      -max_total_time="$secs" -print_final_stats=1 2>&1 | tee "$work/$t.log" | grep -E "^#[0-9]+ *(INITED|DONE)|^Done|ERROR|panicked" || true
    if grep -q "ERROR: libFuzzer\|panicked" "$work/$t.log"; then
      echo "$t: CRASH (see fuzz/artifacts/$t)"; exit 1
    fi
    runs=$(grep -E "^stat::number_of_executed_units" "$work/$t.log" | awk '{print $2}')
    echo "$t: ${runs:-?} inputs in ${secs} s, no crash; $(ls "$work/$t" | wc -l) new corpus inputs found (not kept)"
  done
else
  echo "cargo-fuzz or nightly not available: running the bounded stable loop (cargo install cargo-fuzz for libFuzzer)"
  cargo run --release --bin bounded -- "$secs"
fi
