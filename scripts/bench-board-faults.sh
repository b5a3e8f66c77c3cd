#!/usr/bin/env bash
# The fault matrix on the tick-level board model (firmware/board-model): the
# box's own interrupt handlers, AdcDma and DmaSource on a model of TIM3, TIM5,
# EXTI0, SPI2, DMA1 and the AD7606, one fault per scenario, every delivered
# sample checked against the model's truth. Prints each failing scenario by
# name (at most 3 per class), a table per fault class, and last:
#   scenarios N, silent corruptions C, uncounted losses U
# Exit status 1 when C or U is not 0.
#
#   bash scripts/bench-board-faults.sh                    # all scenarios
#   bash scripts/bench-board-faults.sh --stride 10        # every 10th
#   bash scripts/bench-board-faults.sh --legacy-restart   # the old restart path
#   bash scripts/bench-board-faults.sh --only 5663        # one scenario, in detail
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
cargo build --release --quiet -p plinth-board-model --bin board-faults
exec "$CARGO_TARGET_DIR/release/board-faults" "$@"
