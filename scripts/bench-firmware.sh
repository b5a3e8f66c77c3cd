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
#
#   bash scripts/bench-firmware.sh                 # print the figures
#   bash scripts/bench-firmware.sh --update-docs   # and write the cycle table
#                                                  # into firmware/README.md
set -euo pipefail
update_docs=0
[ "${1:-}" = "--update-docs" ] && update_docs=1
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

# The board model's per-handler figures (a clean run, 96-vector halves).
model=$(bash ../scripts/bench-board-faults.sh --budget)
echo "$model"
# Instructions of each compiled interrupt handler in the box image, every
# call it makes expanded at its call site (each callee counted once per
# call site, every branch counted: an upper bound of one pass).
objdump_tool="$(dirname "$size_tool")/llvm-objdump"
handlers=$("$objdump_tool" -d --no-show-raw-insn "$box_elf" | python3 -c '
import re, sys
funcs, cur = {}, None
for line in sys.stdin:
    m = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
    if m:
        cur = m.group(1); funcs[cur] = [0, []]; continue
    if not line.strip():
        cur = None; continue
    m = re.match(r"^\s+[0-9a-f]+:\s+(\S+)\s*(.*)$", line)
    if cur and m:
        funcs[cur][0] += 1
        t = re.search(r"<([^+>]+)(\+0x[0-9a-f]+)?>", m.group(2))
        if m.group(1).split(".")[0] in ("bl", "blx", "b") and t and t.group(1) != cur:
            funcs[cur][1].append(t.group(1))
def expanded(f, stack=()):
    if f not in funcs or f in stack:
        return 0
    return funcs[f][0] + sum(expanded(c, stack + (f,)) for c in funcs[f][1])
for h in ["EXTI0", "DMA1_STREAM3", "TIM5", "SPI2", "DMA1_STREAM5", "SysTick"]:
    print(h, expanded(h))
')
echo "$handlers"

python3 - "$flash" "$ram" \
  "$(get extractor_instr_per_channel_sample_between_edges)" \
  "$(get extractor_instr_per_channel_sample_with_edges)" \
  "$(get rls_instr_per_update)" "$(get rls_instr_per_estimate)" \
  "$(get receive_instr_per_frame)" "$(get frame_bytes)" \
  "$box_flash" "$box_ram" "$(get acquisition_instr_per_half)" \
  "$model" "$handlers" "$update_docs" <<'PY'
import sys
flash, ram = int(sys.argv[1]), int(sys.argv[2])
ex_steady, ex_all, rls, est, rx, frame_bytes = map(float, sys.argv[3:9])
box_flash, box_ram, acq_half = int(sys.argv[9]), int(sys.argv[10]), float(sys.argv[11])
update_docs = sys.argv[14] == "1"
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
# (firmware/README.md, "Cycle budget on the board"). No hand arithmetic:
#  - each interrupt handler's cost per call = exception entry + exit (the
#    board model's 12 + 12 cycles) + its register accesses as the board
#    model counts them when it runs the handler (`board-faults --budget`,
#    4 cycles each) + the compiled handler's other instructions (its
#    instruction count in the plinth-box ELF with its calls expanded,
#    every branch counted: an upper bound, one cycle each);
#  - the consumer's copy, scaling and edge placement and the extractor:
#    measured under QEMU (one instruction per cycle);
#  - the SPI DMA's 16 half-words per conversion may stall the CPU 2 cycles
#    each at the bus matrix (upper bound).
import subprocess
model = {}
for line in sys.argv[12].splitlines():
    f = line.split()
    if f and f[0] == "MODEL":
        model[f[1]] = dict(prio=int(f[3]), calls=int(f[5]), acc=float(f[7]), cyc=float(f[9]), conv=int(f[11]))
instr = {}
for line in sys.argv[13].splitlines():
    name, n = line.split()
    instr[name] = int(n)
vector = {"busy_fell": "EXTI0", "adc_half": "DMA1_STREAM3", "keyphasor": "TIM5", "spi_error": "SPI2"}
# The table firmware/README.md carries (and README.md quotes), generated
# here so that both files show one set of figures.
kp_hz = 50.0   # keyphasor of a 3000 rpm machine: one TIM5 capture per revolution
rate_hz = 84e6 / 1641   # the box's sample rate (TIM3 period)
label = {"busy_fell": "`busy_fell` (EXTI0, priority {p})", "adc_half": "`adc_half` (DMA1_STREAM3, {p})",
         "keyphasor": "`keyphasor` (TIM5, {p}), 50 Hz keyphasor"}
rows = ["| part | calls per conversion | register accesses per call (model) | compiled instructions | cycles per call | cycles per conversion |",
        "| --- | --- | --- | --- | --- | --- |"]
per_conv = 0.0
for name in ["busy_fell", "adc_half", "keyphasor"]:
    m = model[name]
    n = instr.get(vector[name], 0)
    per_call = 24 + 4 * m["acc"] + max(0.0, n - m["acc"])
    rate = kp_hz / rate_hz if name == "keyphasor" else m["calls"] / m["conv"]
    per_conv += rate * per_call
    shown = f"1/{1/rate:.0f}" if 0.005 < rate < 0.5 else (f"{rate:.0f}" if rate >= 0.5 else f"{rate:.4f}")
    rows.append(f"| {label[name].format(p=m['prio'])} | {shown} | {m['acc']:.0f} | {n} | {per_call:.0f} | {rate*per_call:.1f} |")
dma_stall = 16 * 2
consumer = acq_half / 96
extractor = ex_all * ch
rows.append(f"| SPI DMA: 16 half-words, <= 2 cycles of bus-matrix stall each | | | | | <= {dma_stall} |")
rows.append(f"| consumer: copy 96 vectors out of the DMA half, codes -> volts, saturation, edges (QEMU) | | | | | {consumer:.1f} |")
rows.append(f"| phasor extractor, 8 channels incl. per-revolution work (QEMU) | | | | | {extractor:.1f} |")
per_conv += dma_stall + consumer + extractor
rows.append(f"| **total (estimate)** | | | | | **{per_conv:.0f}** |")
acq_load = fs * per_conv
spi_err = instr.get("SPI2", 0)
rows.append("")
rows.append(f"= {acq_load/1e6:.1f} M cycles/s, **{100*acq_load/mips:.1f} %** of a 168 MHz M4F at 51.2 kHz "
            f"(estimate); RLS for 4 pedestals at 200 Hz adds {100*800*(rls+est)/mips:.1f} %. "
            f"`spi_error` ({spi_err} instructions) runs only on a fault.")
rows.append("")
rows.append(f"Image: **{box_flash/1024:.1f} KiB ({box_flash} B) flash, {box_ram/1024:.1f} KiB ({box_ram} B) static RAM** "
            f"(STM32F401 class: <= 128 KiB {ok(box_flash <= 131072)}, <= 64 KiB {ok(box_ram <= 65536)}).")
print()
print("\n".join(rows))
sclk, conv_us = 10.5e6, 4.15
read_us = 16 * 8 / sclk * 1e6
print(f"SPI read per conversion: 16 bytes at {sclk/1e6:.1f} MHz = {read_us:.1f} us + conversion {conv_us} us "
      f"= {read_us+conv_us:.1f} us of the {1e6/fs:.2f} us sample period")
if update_docs:
    begin, end = "<!-- cycle-table: bash scripts/bench-firmware.sh --update-docs -->", "<!-- end cycle-table -->"
    path = "README.md"
    text = open(path).read()
    a, b = text.index(begin) + len(begin), text.index(end)
    open(path, "w").write(text[:a] + "\n" + "\n".join(rows) + "\n" + text[b:])
    print(f"firmware/{path}: cycle table updated")
PY
