#!/usr/bin/env bash
# identify's cost at 200 / 2 000 / 20 000 speeds, OLS and ML, on a noisy
# two-bearing run-down made by `plinth simulate` (the paper's damped machine,
# 1 % noise), and `accuracy --draws 200` on 1 and 2 threads (wall time; the
# two must print the same table). Prints one line per case: wall seconds
# (best of 3) and CPU seconds. Targets (issue 19): ML at 20 001 speeds ≤ 1 s,
# OLS ≤ 0.3 s, accuracy ≤ 10 s on 2 cores.
#   scripts/bench-identify.sh            # all
#   SKIP_ACCURACY=1 scripts/bench-identify.sh
#   PLINTH=/tmp/old/plinth scripts/bench-identify.sh   # another build, to compare
set -euo pipefail
cd "$(dirname "$0")/.."
# PLINTH=path/to/plinth times that binary instead of building this tree's.
if [ -z "${PLINTH:-}" ]; then
  cargo build --release -q -p plinth
fi
plinth=${PLINTH:-${CARGO_TARGET_DIR:-target}/release/plinth}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
machine=examples/feng-hahn-1997-damped.toml

# Best-of-3 wall time and the CPU time of that run, in seconds.
timed() {
  local best="" cpu=""
  for _ in 1 2 3; do
    # identify exits 2 when it flags a pedestal: the time is what counts here.
    /usr/bin/time -o "$work/time" -f "%e %U %S" "$@" >/dev/null 2>&1 || true
    local wall user sys
    read -r wall user sys < <(tail -1 "$work/time")
    if [ -z "$best" ] || awk -v a="$wall" -v b="$best" 'BEGIN{exit !(a<b)}'; then
      best=$wall
      cpu=$(awk -v u="$user" -v s="$sys" 'BEGIN{printf "%.2f", u+s}')
    fi
  done
  echo "$best $cpu"
}

printf "%-32s %10s %10s\n" "case" "wall [s]" "cpu [s]"
for n in 200 2000 20000; do
  step=$(awk -v n="$n" 'BEGIN{printf "%.10g", 200/n}')
  run="$work/run$n"
  "$plinth" simulate "$machine" --speeds "5:205:$step" --noise 0.01 --out "$run" >/dev/null
  speeds=$(( $(wc -l <"$run/measurements.csv") / 2 ))
  for est in ols ml; do
    read -r wall cpu <<<"$(timed "$plinth" identify "$run" --estimator "$est")"
    printf "%-32s %10s %10s\n" "identify $est, $speeds speeds" "$wall" "$cpu"
  done
done

if [ -z "${SKIP_ACCURACY:-}" ]; then
  for threads in 1 2; do
    start=$(date +%s.%N)
    RAYON_NUM_THREADS=$threads "$plinth" accuracy "$machine" --noise 0.01 --draws 200 \
      >"$work/accuracy$threads.txt"
    end=$(date +%s.%N)
    printf "%-32s %10.2f\n" "accuracy 200 draws, $threads thread(s)" \
      "$(awk -v a="$start" -v b="$end" 'BEGIN{print b-a}')"
  done
  if cmp -s "$work/accuracy1.txt" "$work/accuracy2.txt"; then
    echo "accuracy: the same table on 1 and 2 threads"
  else
    echo "accuracy: the tables on 1 and 2 threads DIFFER" >&2
    diff "$work/accuracy1.txt" "$work/accuracy2.txt" >&2 || true
    exit 1
  fi
fi
