#!/usr/bin/env bash
# Builds plinth-box, the field box image for the reference board
# (STM32F407G-DISC1 + AD7606 module; firmware/README.md), release, for
# thumbv7em-none-eabihf, and prints the ELF's path on its last line.
# Extra arguments go to cargo (e.g. `--features log` for the defmt log over
# RTT with a probe, `--features bench` for the cycle counts). The default
# is the field image: no logging (nothing can mask BUSY's interrupt); the
# script checks that in the ELF (no RTT, a defmt logger that masks nothing)
# and fails otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."

rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
# defmt keeps only errors unless told otherwise: the box's start-up and
# fault lines are info and warn.
export DEFMT_LOG="${DEFMT_LOG:-info}"
cargo build -p plinth-box --target thumbv7em-none-eabihf --release "$@" >&2
elf="$(cd "${CARGO_TARGET_DIR:-target}" && pwd)/thumbv7em-none-eabihf/release/plinth-box"

# The field image (no cargo arguments, or PLINTH_BOX_CHECK=1) must carry no
# logging that can hold BUSY's interrupt off: no RTT control block, no
# defmt-rtt code, and a defmt logger whose acquire/write/release neither
# mask interrupts nor call anything (firmware/README.md, "Logging").
check_field_image() {
  local tools nm objdump bad=0 f body
  tools="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
  nm="$tools/llvm-nm"; objdump="$tools/llvm-objdump"
  [ -x "$nm" ] && [ -x "$objdump" ] || { echo "no llvm-nm/llvm-objdump in $tools ('rustup component add llvm-tools')" >&2; return 1; }
  if "$nm" "$1" | grep -Eiq '_SEGGER_RTT|defmt_rtt'; then
    echo "field image check: $1 links RTT logging ($("$nm" "$1" | grep -Ei '_SEGGER_RTT|defmt_rtt' | head -1))" >&2
    bad=1
  fi
  for f in _defmt_acquire _defmt_write _defmt_release; do
    body="$("$objdump" -d --no-show-raw-insn --disassemble-symbols="$f" "$1" | grep -E '^ +[0-9a-f]+:' || true)"
    if [ -z "$body" ]; then
      echo "field image check: no $f in $1" >&2; bad=1
    elif echo "$body" | grep -Eq 'cpsid|msr[[:space:]]+(primask|basepri)|[[:space:]]bl[[:space:]]|[[:space:]]blx?[[:space:]]|svc|bkpt'; then
      echo "field image check: $f masks interrupts or calls out:" >&2; echo "$body" >&2; bad=1
    fi
  done
  [ "$bad" = 0 ] && echo "field image check: no RTT, defmt logger masks nothing ($(basename "$1"))" >&2
  return "$bad"
}
if [ $# -eq 0 ] || [ "${PLINTH_BOX_CHECK:-0}" = 1 ]; then
  check_field_image "$elf"
fi
echo "$elf"
