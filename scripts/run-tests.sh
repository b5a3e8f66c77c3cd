#!/usr/bin/env bash
# Runs every test of the workspace in release, like `cargo test --workspace
# --release`, but TEST_JOBS test binaries at a time (default: the number of
# cores) instead of one after the other. `cargo test` runs a binary's tests
# in parallel but its binaries in turn, so a binary holding one long test
# (the QEMU end-to-end runs, one diagnose of a hard run) leaves the other
# core idle for its whole length; here the next binary takes that core.
# Binaries known to be long are started first so the lanes end together
# (the order only: every binary runs, and any failure fails the whole).
#
# Each binary runs in its package's directory (as under cargo), its
# output kept in a log that is printed whole if it fails (the
# passing ones print their `test result` line). Doc-tests run last, through
# cargo.
#
# Usage: bash scripts/run-tests.sh [extra harness args, e.g. a name filter]
set -euo pipefail
cd "$(dirname "$0")/.."

jobs="${TEST_JOBS:-$(nproc 2>/dev/null || echo 2)}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Build every test binary once; list "<package dir>\t<executable>" per
# line from cargo's JSON messages (one message a line; a test binary is an
# artifact whose *profile* says test, which leaves out the `plinth` binary
# the tests call).
cargo test --workspace --release --no-run --message-format=json-render-diagnostics \
  > "$work/build.json"
grep '"reason":"compiler-artifact"' "$work/build.json" \
  | grep -E '"profile":\{[^}]*"test":true' \
  | grep '"executable":"' \
  | sed -E 's/.*"manifest_path":"([^"]*)\/Cargo\.toml".*"executable":"([^"]*)".*/\1\t\2/' \
  > "$work/all.txt"
if [ ! -s "$work/all.txt" ]; then
  echo "run-tests: no test binaries found in cargo's build output" >&2
  exit 1
fi

# Long binaries first (the order only: an unknown or renamed binary runs in
# cargo's order after these).
first="unseen_machine diagnose_combined firmware_qemu foundation_ross robustness_diagnose plinth qemu_stream identify_conventions unseen_machine_4 unseen_machine_3 unseen_machine_2"
: > "$work/order.txt"
for name in $first; do
  grep -E "/${name}-[0-9a-f]+$" "$work/all.txt" >> "$work/order.txt" || true
done
grep -v -x -F -f "$work/order.txt" "$work/all.txt" >> "$work/order.txt" || true
mkdir -p "$work/logs" "$work/failed"

# One binary: run in its package's directory (as cargo does), log kept;
# prints its `test result` line, or the whole log when it fails.
run_one() {
  local dir="$1" exe="$2"
  shift 2
  local name log start rc=0 secs
  name="$(basename "$exe")"
  log="$work/logs/$name.log"
  start=$(date +%s)
  (cd "$dir" && "$exe" "$@") > "$log" 2>&1 || rc=$?
  secs=$(( $(date +%s) - start ))
  if [ "$rc" -eq 0 ]; then
    printf '%-40s %4d s  %s\n' "${name%-*}" "$secs" \
      "$(grep -E '^test result:' "$log" | tail -1)"
  else
    printf '\n=== FAILED: %s (%s, exit %d, %d s)\n' "${name%-*}" "$exe" "$rc" "$secs"
    cat "$log"
    touch "$work/failed/$name"
  fi
}

count=$(wc -l < "$work/order.txt")
echo "running $count test binaries, $jobs at a time"
running=0
while IFS=$'\t' read -r dir exe; do
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  run_one "$dir" "$exe" "$@" &
  running=$((running + 1))
done < "$work/order.txt"
wait || true

failed=$(find "$work/failed" -type f | wc -l)
if [ "$failed" -ne 0 ]; then
  echo "run-tests: $failed of $count test binaries FAILED:" \
    "$(find "$work/failed" -type f -printf '%f ' | sed -E 's/-[0-9a-f]+( |$)/ /g')" >&2
  exit 1
fi
echo "run-tests: all $count test binaries passed"

cargo test --workspace --release --doc
