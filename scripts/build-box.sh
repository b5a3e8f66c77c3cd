#!/usr/bin/env bash
# Builds plinth-box, the field box image for the reference board
# (STM32F407G-DISC1 + AD7606 module; firmware/README.md), release, for
# thumbv7em-none-eabihf, and prints the ELF's path on its last line.
# Extra arguments go to cargo (e.g. `--features log` for the defmt log over
# RTT with a probe, `--features bench` for the cycle counts). The default
# is the field image: no logging (nothing can mask BUSY's interrupt).
set -euo pipefail
cd "$(dirname "$0")/.."

rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
# defmt keeps only errors unless told otherwise: the box's start-up and
# fault lines are info and warn.
export DEFMT_LOG="${DEFMT_LOG:-info}"
cargo build -p plinth-box --target thumbv7em-none-eabihf --release "$@" >&2
echo "$(cd "${CARGO_TARGET_DIR:-target}" && pwd)/thumbv7em-none-eabihf/release/plinth-box"
