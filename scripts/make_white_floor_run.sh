#!/bin/sh
# Makes tests/data/three-bearing/white-0.3-2521 (tests/tests/identify_scatter_floor.rs):
# bench_trust's clean case "three-bearing noise 0.3 %" at seed 2521 (scripts/bench_common.py:
# the exact run of tests/machines/three-bearing-tabulated.toml on 5:200:2.5 Hz at 12 digits,
# then 0.3 % white noise without noise columns by scripts/trust_data.py).
# usage: scripts/make_white_floor_run.sh PLINTH_BINARY
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
"$1" simulate "$root/tests/machines/three-bearing-tabulated.toml" --out "$work/exact" \
    --speeds 5:200:2.5 --digits 12 >/dev/null
out="$root/tests/data/three-bearing/white-0.3-2521"
rm -rf "$out"
python3 "$root/scripts/trust_data.py" "$work/exact" "$out" --noise 0.003 --seed 2521
rm -rf "$work"
