#!/usr/bin/env bash
# Plinth's whole test suite: the one command the README gives and CI runs.
# Installs what it needs (the thumbv7em-none-eabihf target, the llvm-tools
# component for the field image's ELF check, qemu-system-arm,
# chromium for the report test).
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n=== %s\n' "$*"; }

step "toolchain: thumbv7em-none-eabihf target"
if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
  rustup target add thumbv7em-none-eabihf
fi

step "toolchain: llvm-tools (llvm-nm, llvm-objdump: the field image's ELF check)"
if ! rustup component list --installed | grep -q '^llvm-tools'; then
  rustup component add llvm-tools
fi

step "qemu-system-arm"
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null
fi

step "chromium (the report is checked in a real headless browser)"
if ! command -v chromium >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi

step "format"
cargo fmt --all -- --check

step "clippy (host crates)"
cargo clippy --workspace --all-targets -- -D warnings

step "clippy (firmware, the board image and shared for thumbv7em-none-eabihf)"
cargo clippy -p plinth-shared -p plinth-firmware -p plinth-box --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p plinth-box --target thumbv7em-none-eabihf --features bench -- -D warnings

step "cross-build: plinth-shared and the firmware image for thumbv7em-none-eabihf"
cargo build -p plinth-shared --target thumbv7em-none-eabihf --release
# (into the directory the QEMU tests build their image in, so theirs is a no-op)
cargo build -p plinth-firmware --target thumbv7em-none-eabihf --release \
  --target-dir "${CARGO_TARGET_DIR:-target}/qemu-image"

step "cross-build: plinth-box, the board image (STM32F407G-DISC1 + AD7606)"
bash scripts/build-box.sh

step "tests (host, simulated hardware, QEMU end to end)"
# `cargo test --workspace --release`, two test binaries at a time (the
# script says why; TEST_JOBS sets how many).
bash scripts/run-tests.sh
