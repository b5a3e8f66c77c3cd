#!/usr/bin/env bash
# Firmware performance figures (issue 4): instruction counts of the hot paths
# measured under QEMU with -icount shift=10 (SysTick: 172.032 ticks per
# instruction at 168 MHz), flash and RAM of the image from llvm-size, and the
# budget for 8 channels at 51.2 kHz on a 168 MHz Cortex-M4F.
#
# Builds inside firmware/ so that firmware/.cargo/config.toml (target, size
# profile) applies: the measured image is the one `cargo run --release` runs.
set -euo pipefail
cd "$(dirname "$0")/../firmware"

export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/../target}"
rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
cargo build --release --bins
out="$CARGO_TARGET_DIR/thumbv7em-none-eabihf/release"

size_tool=""
for c in "$(rustc --print sysroot)/lib/rustlib/x86_64-unknown-linux-gnu/bin/llvm-size" \
  $(ls ~/.rustup/toolchains/*/lib/rustlib/x86_64-unknown-linux-gnu/bin/llvm-size 2>/dev/null) \
  "$(command -v llvm-size || true)" "$(command -v arm-none-eabi-size || true)"; do
  if [ -n "$c" ] && [ -x "$c" ]; then size_tool="$c"; break; fi
done
[ -n "$size_tool" ] || { echo "no llvm-size: rustup component add llvm-tools" >&2; exit 1; }

bench=$(timeout 300 qemu-system-arm -M netduinoplus2 -display none -monitor none -serial null \
  -semihosting-config enable=on,target=native -icount shift=10 \
  -kernel "$out/plinth-firmware-bench" | tr -c '[:print:]\n' '\n' | grep '^BENCH ')
echo "$bench"
get() { echo "$bench" | awk -v k="$1" '$2 == k {print $3}'; }

# Flash = vector table + code + read-only data + initialised data; RAM =
# .data + .bss + .uninit (static; the stack comes on top, at the end of RAM).
read -r flash ram < <("$size_tool" -A "$out/plinth-firmware" | awk '
  $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" {f += $2}
  $1 == ".data" {f += $2; r += $2}
  $1 == ".bss" || $1 == ".uninit" {r += $2}
  END {print f, r}')

python3 - "$flash" "$ram" \
  "$(get extractor_instr_per_channel_sample_between_edges)" \
  "$(get extractor_instr_per_channel_sample_with_edges)" \
  "$(get rls_instr_per_update)" "$(get rls_instr_per_estimate)" \
  "$(get receive_instr_per_frame)" "$(get frame_bytes)" <<'PY'
import sys
flash, ram = int(sys.argv[1]), int(sys.argv[2])
ex_steady, ex_all, rls, est, rx, frame_bytes = map(float, sys.argv[3:9])
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
PY
