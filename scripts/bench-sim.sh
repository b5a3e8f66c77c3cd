#!/usr/bin/env bash
# Unbalance-response sweep, Plinth vs ROSS, on the same model and speeds
# (tests/reference/ross/machine-a.toml, 1000 speeds 5..200 Hz).
# Prints both figures and their ratio. Needs python3 with ross 2.3.0.
set -euo pipefail
cd "$(dirname "$0")/.."
log=$(mktemp)
cargo bench -p plinth --bench unbalance_sweep -- --noplot "assembled once" 2>&1 | tee "$log" | grep -E "DOF|time:" || true
plinth_s=$(grep -A2 "assembled once" "$log" | grep -oE "time: +\[[^]]*\]" | head -1 \
  | awk '{v=$4; u=$5; f=(u=="ms")?1e-3:(u=="µs"||u=="us")?1e-6:(u=="ns")?1e-9:1; printf "%.6g", v*f}')
ross_line=$(python3 tests/reference/ross/make_reference.py --time 2>/dev/null | grep '^ROSS')
echo "$ross_line"
ross_s=$(echo "$ross_line" | grep -oE '[0-9.]+ s total' | awk '{print $1}')
echo "Plinth: ${plinth_s} s per 1000 speeds; ROSS: ${ross_s} s per 1000 speeds"
awk -v p="$plinth_s" -v r="$ross_s" 'BEGIN { if (p > 0) printf "Plinth is %.0fx faster than ROSS\n", r / p }'
rm -f "$log"
