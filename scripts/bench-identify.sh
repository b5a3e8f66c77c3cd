#!/usr/bin/env bash
# identify's cost at 200 / 2 000 / 20 000 speeds, OLS and ML, on a noisy
# two-bearing run-down made by `plinth simulate` (the paper's damped machine,
# 1 % noise), and `accuracy --draws 200` on 1 and 2 threads (wall time; the
# two must print the same table). Prints one line per case: the median over
# ROUNDS (default 3) interleaved runs (OLS, ML, OLS, ML, ...; with BASELINE
# set, that binary's run next to each) of the CPU seconds (user + system)
# and of the wall seconds, and the load average before and after (CPU time
# is what to compare on a loaded machine). Targets (issue 19): ML at 20 001
# speeds ≤ 1 s, OLS ≤ 0.3 s, accuracy ≤ 10 s on 2 cores.
#   scripts/bench-identify.sh            # all
#   SKIP_ACCURACY=1 scripts/bench-identify.sh
#   PLINTH=OLD/plinth scripts/bench-identify.sh    # another build
#   BASELINE=OLD/plinth SKIP_ACCURACY=1 scripts/bench-identify.sh  # both, interleaved
set -euo pipefail
cd "$(dirname "$0")/.."
# PLINTH=path/to/plinth times that binary instead of building this tree's.
if [ -z "${PLINTH:-}" ]; then
  cargo build --release -q -p plinth
fi
plinth=${PLINTH:-${CARGO_TARGET_DIR:-target}/release/plinth}
rounds=${ROUNDS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
machine=examples/feng-hahn-1997-damped.toml

# One run: prints "cpu wall" in seconds.
timed() {
  # identify exits 2 when it flags a pedestal: the time is what counts here.
  /usr/bin/time -o "$work/time" -f "%e %U %S" "$@" >/dev/null 2>&1 || true
  local wall user sys
  read -r wall user sys < <(tail -1 "$work/time")
  awk -v u="$user" -v s="$sys" -v w="$wall" 'BEGIN{printf "%.2f %.2f\n", u+s, w}'
}

# Median of the numbers on stdin.
median() {
  sort -g | awk '{v[NR]=$1} END{if (NR%2) print v[(NR+1)/2]; else printf "%.2f\n", (v[NR/2]+v[NR/2+1])/2}'
}

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
printf "%-40s %10s %10s\n" "case" "cpu [s]" "wall [s]"
binaries=("$plinth")
if [ -n "${BASELINE:-}" ]; then
  binaries+=("$BASELINE")
fi
for n in 200 2000 20000; do
  step=$(awk -v n="$n" 'BEGIN{printf "%.10g", 200/n}')
  run="$work/run$n"
  "$plinth" simulate "$machine" --speeds "5:205:$step" --noise 0.01 --out "$run" >/dev/null
  speeds=$(( $(wc -l <"$run/measurements.csv") / 2 ))
  : >"$work/times"
  for _ in $(seq "$rounds"); do
    for est in ols ml; do
      for b in "${!binaries[@]}"; do
        echo "$b $est $(timed "${binaries[$b]}" identify "$run" --estimator "$est")" >>"$work/times"
      done
    done
  done
  for est in ols ml; do
    for b in "${!binaries[@]}"; do
      label="identify $est, $speeds speeds"
      [ "$b" -gt 0 ] && label="$label (baseline)"
      cpu=$(awk -v b="$b" -v e="$est" '$1==b && $2==e {print $3}' "$work/times" | median)
      wall=$(awk -v b="$b" -v e="$est" '$1==b && $2==e {print $4}' "$work/times" | median)
      printf "%-40s %10s %10s\n" "$label" "$cpu" "$wall"
    done
  done
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

if [ -z "${SKIP_ACCURACY:-}" ]; then
  for threads in 1 2; do
    start=$(date +%s.%N)
    RAYON_NUM_THREADS=$threads "$plinth" accuracy "$machine" --noise 0.01 --draws 200 \
      >"$work/accuracy$threads.txt"
    end=$(date +%s.%N)
    printf "%-40s %10s %10.2f\n" "accuracy 200 draws, $threads thread(s)" "" \
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
