#!/usr/bin/env bash
# Regenerates examples/field/ (the README's field quick start): simulates the
# damped paper machine with `plinth simulate` on a fine speed grid, then
# scripts/make-field-example.py writes a vector table + layout, a WAV
# recording + channels file, bearings.csv and truth.json from it.
#
#   bash scripts/make-field-example.sh            # into examples/field/
set -euo pipefail
cd "$(dirname "$0")/.."
out=examples/field
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build --release -q -p plinth
plinth="${CARGO_TARGET_DIR:-target}/release/plinth"
"$plinth" --quiet simulate examples/feng-hahn-1997-damped.toml --out "$tmp/sim" --speeds 15:75:0.05 >/dev/null
python3 scripts/make-field-example.py "$tmp/sim" "$out"
ls -l "$out"
