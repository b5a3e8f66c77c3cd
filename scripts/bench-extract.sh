#!/usr/bin/env bash
# Throughput and peak memory of `plinth extract` (both passes: the keyphasor
# edges, then the phasors) on a 60 s, 9-channel, 51.2 kHz 32-bit float WAV
# (110 MB, 3.07 M frames): a run-down 80 -> 20 Hz at 1 Hz/s, 8 vibration
# channels (1X + 2X + noise) and a notch keyphasor with 2-degree edges (so
# the edge smoothing is engaged: the slower path). Made with numpy.
#
#   scripts/bench-extract.sh [PLINTH] [RUNS]
#
# PLINTH: the binary (default target/release/plinth); RUNS: extractions
# (default 3). Prints each run's throughput line (samples/s per channel, as
# `plinth extract` reports it), the median, and the peak resident memory
# (/usr/bin/time -v, when present).
set -euo pipefail
cd "$(dirname "$0")/.."
plinth=${1:-target/release/plinth}
runs=${2:-3}
py=${PYTHON:-python3}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$py" - "$dir" <<'EOF'
import math, struct, sys
import numpy as np
d, fs, secs, ch = sys.argv[1], 51200, 60.0, 8
t = np.arange(int(fs * secs)) / fs
f0, rate = 80.0, 1.0
theta = 2 * math.pi * (f0 * t - 0.5 * rate * t * t)
rng = np.random.default_rng(1)
cols = []
for c in range(ch):
    a = 0.5 + 0.1 * c
    cols.append(a * np.cos(theta - 0.3 * c) + 0.05 * a * np.cos(2 * theta + c)
                + 1e-3 * rng.standard_normal(len(t)) + (-9.0 if c % 4 < 2 else 0.0))
ramp, width = math.radians(2.0), math.radians(12.0)
phi = np.mod(theta + 0.5 * ramp, 2 * math.pi)
cols.append(np.interp(phi, [0, ramp, width, width + ramp, 2 * math.pi], [-1.0, -9.0, -9.0, -1.0, -1.0]))
data = np.array(cols, dtype="<f4").T.tobytes()
n = ch + 1
with open(f"{d}/rec.wav", "wb") as w:
    w.write(b"RIFF" + struct.pack("<I", 4 + 8 + 16 + 8 + len(data)) + b"WAVE")
    w.write(b"fmt " + struct.pack("<IHHIIHH", 16, 3, n, fs, fs * n * 4, n * 4, 32))
    w.write(b"data" + struct.pack("<I", len(data)) + data)
lines = ["revolutions = 4", "", "[keyphasor]", f"channel = {ch}", "threshold_v = -5.0", 'edge = "falling"', ""]
for c in range(ch):
    b, q, a = f"B{c // 4 + 1}", ("rel", "rel", "ped", "ped")[c % 4], (45.0, -45.0, 0.0, 90.0)[c % 4]
    lines += ["[[channel]]", f"index = {c}", f'bearing = "{b}"', f'quantity = "{q}"', f"angle_deg = {a}",
              'sensor = "proximity"', "sensitivity = 7.87", 'sensitivity_unit = "V/mm"', ""]
open(f"{d}/channels.toml", "w").write("\n".join(lines))
with open(f"{d}/bearings.csv", "w") as b:
    b.write("speed_hz,bearing,kyy,kyz,kzy,kzz,cyy,cyz,czy,czz\n")
    for s in range(10, 91):
        for name in ("B1", "B2"):
            b.write(f"{s},{name},3e8,1e8,2e7,7e7,3e6,8e5,8e5,5e5\n")
EOF
ls -la "$dir/rec.wav" | awk '{printf "recording: %.0f MB\n", $5 / 1e6}'
figures=()
for i in $(seq 1 "$runs"); do
  rm -rf "$dir/run"
  if [ -x /usr/bin/time ]; then
    /usr/bin/time -v "$plinth" extract "$dir/rec.wav" --channels "$dir/channels.toml" --bearings "$dir/bearings.csv" --out "$dir/run" \
      >"$dir/out" 2>"$dir/err" || { cat "$dir/err"; exit 1; }
    peak=$(grep "Maximum resident" "$dir/err" | awk '{printf "%.1f MB", $6 / 1024}')
  else
    "$plinth" extract "$dir/rec.wav" --channels "$dir/channels.toml" --bearings "$dir/bearings.csv" --out "$dir/run" >"$dir/out" 2>"$dir/err" \
      || { cat "$dir/err"; exit 1; }
    peak="(no /usr/bin/time)"
  fi
  line=$(grep '^throughput' "$dir/out")
  echo "run $i: $line, peak resident $peak"
  figures+=("$(echo "$line" | awk '{print $2}')")
done
printf '%s\n' "${figures[@]}" | sort -g | awk '{v[NR]=$1} END {printf "median: %.3g samples/s per channel over %d runs\n", v[int((NR+1)/2)], NR}'
