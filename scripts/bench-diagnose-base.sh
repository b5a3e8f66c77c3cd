#!/usr/bin/env bash
# The cost of fitting bases: `plinth diagnose --json` on stored ROSS runs
# with a flexible base or sub-base (the unseen_machine test's sub-base run,
# the fourth machine's bedplate, the third machine's baseplate with runout)
# and `plinth identify --unmeasured-base` on the base runs. Prints one line
# per case: the median over ROUNDS (default 1) of the CPU seconds (user +
# system) and the wall seconds, and the load average before and after (CPU
# time is what to compare on a loaded machine). With BASELINE set, that
# binary runs next to each case and the line says whether the two outputs
# are byte-identical (the speed-ups of session 34 must not change a number).
#   scripts/bench-diagnose-base.sh
#   PLINTH=NEW/plinth BASELINE=OLD/plinth scripts/bench-diagnose-base.sh
#   CASES=identify scripts/bench-diagnose-base.sh     # only identify's fits
set -euo pipefail
cd "$(dirname "$0")/.."
# PLINTH=path/to/plinth times that binary instead of building this tree's.
if [ -z "${PLINTH:-}" ]; then
  cargo build --release -q -p plinth
fi
plinth=${PLINTH:-${CARGO_TARGET_DIR:-target}/release/plinth}
rounds=${ROUNDS:-1}
cases=${CASES:-diagnose identify}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
data=tests/data

# One run of "$@" with stdout to $out: prints "cpu wall" in seconds.
timed() {
  local out=$1
  shift
  # diagnose and identify exit non-zero when they flag something: the
  # time and the output are what count here.
  /usr/bin/time -o "$work/time" -f "%e %U %S" "$@" >"$out" 2>/dev/null || true
  local wall user sys
  read -r wall user sys < <(tail -1 "$work/time")
  awk -v u="$user" -v s="$sys" -v w="$wall" 'BEGIN{printf "%.2f %.2f\n", u+s, w}'
}

median() {
  sort -g | awk '{v[NR]=$1} END{if (NR%2) print v[(NR+1)/2]; else printf "%.2f\n", (v[NR/2]+v[NR/2+1])/2}'
}

# One case: a name, then the command's arguments after the binary.
bench() {
  local name=$1
  shift
  local load0 same=""
  load0=$(cut -d' ' -f1 /proc/loadavg)
  : >"$work/new" && : >"$work/old"
  for _ in $(seq "$rounds"); do
    timed "$work/out-new" "$plinth" "$@" >>"$work/new"
    if [ -n "${BASELINE:-}" ]; then
      timed "$work/out-old" "$BASELINE" "$@" >>"$work/old"
      if cmp -s "$work/out-new" "$work/out-old"; then same="identical"; else same="DIFFERENT"; fi
    fi
  done
  local cpu wall line
  cpu=$(cut -d' ' -f1 "$work/new" | median)
  wall=$(cut -d' ' -f2 "$work/new" | median)
  line=$(printf "%-34s cpu %7.2f s  wall %7.2f s" "$name" "$cpu" "$wall")
  if [ -n "${BASELINE:-}" ]; then
    line+=$(printf "  | baseline cpu %7.2f s  wall %7.2f s  output %s" \
      "$(cut -d' ' -f1 "$work/old" | median)" "$(cut -d' ' -f2 "$work/old" | median)" "$same")
  fi
  echo "$line  (load $load0 -> $(cut -d' ' -f1 /proc/loadavg))"
}

for c in $cases; do
  case $c in
    diagnose)
      bench "diagnose ross-unseen/sub-base" diagnose "$data/ross-unseen/sub-base" \
        --machine "$data/ross-unseen/unseen-four.toml" --json
      bench "diagnose ross-unseen-4/base" diagnose "$data/ross-unseen-4/base" \
        --machine "$data/ross-unseen-4/unseen-flex.toml" --json
      bench "diagnose ross-unseen-3/base-runout" diagnose "$data/ross-unseen-3/base-runout" \
        --machine "$data/ross-unseen-3/unseen-train.toml" --json
      ;;
    identify)
      bench "identify ross-unseen-4/base" identify "$data/ross-unseen-4/base" \
        --unmeasured-base B1,B2 --json
      bench "identify ross-unseen-3/base-runout" identify "$data/ross-unseen-3/base-runout" \
        --unmeasured-base B2,B3 --json
      bench "identify ross-unseen-2/base-runout-delay" identify \
        "$data/ross-unseen-2/base-runout-delay" --unmeasured-base B1,B2 --json
      ;;
    *)
      echo "unknown case $c (diagnose, identify)" >&2
      exit 2
      ;;
  esac
done
