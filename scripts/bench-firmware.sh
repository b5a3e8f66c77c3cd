#!/usr/bin/env bash
# Firmware performance figures (issues 4, 12): instruction counts of the hot
# paths measured under QEMU with -icount shift=10 (SysTick: 172.032 ticks per
# instruction at 168 MHz), flash and RAM of the QEMU image and of plinth-box
# from llvm-size, and the budget for 8 channels at 51.2 kHz on a 168 MHz
# Cortex-M4F (for plinth-box: QEMU counts plus the acquisition path, an
# estimate with its assumptions below).
#
# Builds inside firmware/ so that firmware/.cargo/config.toml (target, size
# profile) applies: the measured image is the one `cargo run --release` runs.
set -euo pipefail
cd "$(dirname "$0")/../firmware"

export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/../target}"
rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
# llvm-size comes with the llvm-tools component (installed as the target is).
size_tool="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-size"
if [ ! -x "$size_tool" ]; then
  rustup component add llvm-tools >&2
fi
[ -x "$size_tool" ] || { echo "no llvm-size at $size_tool after 'rustup component add llvm-tools'" >&2; exit 1; }
cargo build --release --bins
out="$CARGO_TARGET_DIR/thumbv7em-none-eabihf/release"
# The board image (from the workspace root, as scripts/build-box.sh builds it).
box_elf=$(bash ../scripts/build-box.sh | tail -n 1)

bench=$(timeout 300 qemu-system-arm -M netduinoplus2 -display none -monitor none -serial null \
  -semihosting-config enable=on,target=native -icount shift=10 \
  -kernel "$out/plinth-firmware-bench" | tr -c '[:print:]\n' '\n' | grep '^BENCH ')
echo "$bench"
get() { echo "$bench" | awk -v k="$1" '$2 == k {print $3}'; }

# Flash = vector table + code + read-only data + initialised data; RAM =
# .data + .bss + .uninit (static; the stack comes on top, at the end of RAM).
sizes() {
  "$size_tool" -A "$1" | awk '
    $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" {f += $2}
    $1 == ".data" {f += $2; r += $2}
    $1 == ".bss" || $1 == ".uninit" {r += $2}
    END {print f, r}'
}
read -r flash ram < <(sizes "$out/plinth-firmware")
read -r box_flash box_ram < <(sizes "$box_elf")

python3 - "$flash" "$ram" \
  "$(get extractor_instr_per_channel_sample_between_edges)" \
  "$(get extractor_instr_per_channel_sample_with_edges)" \
  "$(get rls_instr_per_update)" "$(get rls_instr_per_estimate)" \
  "$(get receive_instr_per_frame)" "$(get frame_bytes)" \
  "$box_flash" "$box_ram" "$(get acquisition_instr_per_half)" <<'PY'
import sys
flash, ram = int(sys.argv[1]), int(sys.argv[2])
ex_steady, ex_all, rls, est, rx, frame_bytes = map(float, sys.argv[3:9])
box_flash, box_ram, acq_half = int(sys.argv[9]), int(sys.argv[10]), float(sys.argv[11])
ok = lambda c: "ok" if c else "OVER TARGET"
print()
print(f"image: flash {flash} B = {flash/1024:.1f} KiB (target <= 64 KiB: {ok(flash <= 65536)}), "
      f"static RAM {ram} B = {ram/1024:.1f} KiB (target <= 32 KiB: {ok(ram <= 32768)})")
print(f"phasor extractor: {ex_steady:.2f} instructions per channel-sample between keyphasor edges, "
      f"{ex_all:.2f} including the per-revolution work at 50 Hz (target <= 12: {ok(ex_all <= 12)})")
print(f"pedestal RLS: {rls:.0f} instructions per update (one speed, 4 equations; target <= 1500: {ok(rls <= 1500)}), "
      f"{est:.0f} per estimate with standard errors")
print(f"received replay frame ({frame_bytes:.0f} B, 96 ADC codes): {rx:.0f} instructions")
print()
fs, ch, mips = 51200, 8, 168e6
load = fs * ch * ex_all
print(f"8 channels at 51.2 kHz: {fs*ch:.0f} channel-samples/s x {ex_all:.2f} = {load/1e6:.2f} M instructions/s "
      f"= {100*load/mips:.1f} % of a 168 MHz M4F (at one instruction per cycle)")
per_rev = 4 * (rls + est)
print(f"4 pedestals at 200 Hz (one RLS update + estimate each per revolution): 800 x {rls+est:.0f} = "
      f"{800*(rls+est)/1e6:.2f} M instructions/s = {100*800*(rls+est)/mips:.1f} %")
blocks = fs / 12
print(f"replay at real time (12 vectors of 8 channels per frame): {blocks:.0f} frames/s x {rx:.0f} = "
      f"{blocks*rx/1e6:.1f} M instructions/s = {100*blocks*rx/mips:.0f} % (replay only; the ADC path has no decoding)")

# ---- plinth-box on the reference board (STM32F407 + AD7606) ----
print()
print(f"plinth-box image: flash {box_flash} B = {box_flash/1024:.1f} KiB (STM32F401 class <= 128 KiB: "
      f"{ok(box_flash <= 131072)}), static RAM {box_ram} B = {box_ram/1024:.1f} KiB (<= 64 KiB: {ok(box_ram <= 65536)})")
# ESTIMATE until the DWT figures of `plinth-box --features bench` exist
# (firmware/README.md, "Cycle budget on the board"). Assumptions:
#  - one instruction per cycle for the QEMU counts (flash wait states
#    hidden by the ART accelerator; real CPI on an M4 is 1.0-1.3);
#  - exception entry + exit 24 cycles (12 + 12; the ISRs use no FPU, so
#    lazy stacking saves no FP context);
#  - peripheral register access 4 cycles (DMA1/GPIO on AHB1: 2; EXTI on
#    APB2 at 84 MHz: 2-3; rounded up);
#  - the BUSY ISR: 12 instructions, 8 register accesses (EXTI PR, DMA CR
#    read, HIFCR, BSRR x2, NDTR, CR read-modify-write) and a 10-cycle CS
#    pulse, per conversion;
#  - the SPI DMA moves 16 half-words per conversion (8 out, 8 in); each may
#    stall the CPU for 2 cycles at the bus matrix (upper bound);
#  - the half-complete ISR: 10 instructions, 4 register accesses, per 96
#    conversions; keyphasor ISR (~60 cycles at <= 200 Hz) negligible;
#  - every BUSY interrupt wakes the idle loop from WFI; it looks at the
#    completion count, the receive DMA and the clock (4 loads, one of a DMA
#    register) and sleeps again: 25 cycles;
#  - the consumer's copy, scaling and edge placement: measured under QEMU
#    (acquisition_instr_per_half, 96 conversions, one keyphasor edge).
entry_exit, access = 24, 4
busy_isr = entry_exit + 12 + 8 * access + 10
dma_stall = 16 * 2
half_isr = (entry_exit + 10 + 4 * access) / 96
idle_wake = 25
consumer = acq_half / 96
extractor = ex_all * ch
per_conv = busy_isr + dma_stall + idle_wake + half_isr + consumer + extractor
print(f"per conversion (8 channels) [cycles, estimate]: BUSY ISR {busy_isr} + SPI DMA bus stalls <= {dma_stall} "
      f"+ idle wake-up {idle_wake} + half ISR {half_isr:.2f} + consumer copy/scale {consumer:.1f} (QEMU) "
      f"+ extractor {extractor:.1f} (QEMU) = {per_conv:.0f}")
acq_load = fs * per_conv
print(f"box load at 51.2 kHz: {fs:.0f} x {per_conv:.0f} = {acq_load/1e6:.2f} M cycles/s = {100*acq_load/mips:.1f} % "
      f"of 168 MHz, + RLS {100*800*(rls+est)/mips:.1f} % (ESTIMATE, assumptions in scripts/bench-firmware.sh)")
sclk, conv_us = 10.5e6, 4.15
read_us = 16 * 8 / sclk * 1e6
print(f"SPI read per conversion: 16 bytes at {sclk/1e6:.1f} MHz = {read_us:.1f} us + conversion {conv_us} us "
      f"= {read_us+conv_us:.1f} us of the {1e6/fs:.2f} us sample period")
PY
