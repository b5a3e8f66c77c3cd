#!/usr/bin/env bash
# simulate: wall time and peak memory (/usr/bin/time -v) against the number of
# shaft elements. The paper's machine (examples/feng-hahn-1997.toml: disks at
# 0.4 and 0.8 m, oil-film bearings at 0.1 and 1.1 m with pedestals) with its
# shaft cut into 100, 1 000, 10 000 and 100 000 Timoshenko elements (twelve
# sections; the number of elements is limited only by the memory estimate),
# 196 speeds 5..200 Hz. The last column is the largest difference of any
# measured phasor from the 1 000-element run (the converged answer), relative
# to that channel's peak over speed.
# Usage: scripts/bench-simulate-size.sh [ELEMENTS...]
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(100 1000 10000 100000)
cargo build --release -q -p plinth
bin=${CARGO_TARGET_DIR:-target}/release/plinth
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores (wall time grows with the load; CPU time does not)"
printf "%10s %10s %10s %10s %14s %14s\n" elements dofs "wall [s]" "cpu [s]" "peak RSS [MB]" "vs 1000 el."
# The converged reference: 1 000 elements.
sizes=(1000 "${sizes[@]}")
for n in "${sizes[@]}"; do
  [ -d "$work/run$n" ] && continue
  # a overhang elements each side, the 1 m between the bearings in ten
  # 0.1 m sections of b/10 elements (nodes at the disks and bearings).
  a=$((n / 20)); b=$((n - 2 * a)); per=$((b / 10)); a=$(((n - 10 * per) / 2))
  m="$work/m$n.toml"
  {
    echo 'name = "bench"'
    echo '[shaft]'
    echo 'material = { young_modulus = 2.11e11, poisson_ratio = 0.3, density = 7810.0 }'
    echo "[[shaft.sections]]"; echo "length = 0.1"; echo "outer_diameter = 0.1"; echo "elements = $a"
    for _ in $(seq 10); do
      echo "[[shaft.sections]]"; echo "length = 0.1"; echo "outer_diameter = 0.1"; echo "elements = $per"
    done
    echo "[[shaft.sections]]"; echo "length = 0.1"; echo "outer_diameter = 0.1"; echo "elements = $((n - a - 10 * per))"
    for p in 0.4 0.8; do
      echo "[[disks]]"; echo "position = $p"; echo "width = 0.08"; echo "outer_diameter = 0.5"
      echo "inner_diameter = 0.1"; echo "density = 7810.0"; echo "unbalance = 1.0e-4"
    done
    for side in "left 0.1 80.0 10.0e6" "right 1.1 60.0 6.0e6"; do
      set -- $side
      echo "[[bearings]]"; echo "name = \"$1\""; echo "position = $2"
      echo 'oil_film = { diameter = 0.1, length = 0.0254, clearance = 40.0e-6, viscosity = 0.0069, load = "weight" }'
      echo "pedestal = { m = $3, k_y = $4, k_z = 8.0e6, c_y = 100.0, c_z = 100.0 }"
    done
  } > "$m"
  /usr/bin/time -v "$bin" simulate "$m" --out "$work/run$n" > "$work/out$n" 2> "$work/time$n" || {
    cat "$work/time$n"; exit 1; }
  secs=$(grep "Elapsed (wall clock)" "$work/time$n" | awk '{print $NF}' | awk -F: '{ if (NF==3) print $1*3600+$2*60+$3; else print $1*60+$2 }')
  kb=$(grep "Maximum resident set size" "$work/time$n" | awk '{print $NF}')
  cpu=$(awk '/User time|System time/ {s += $NF} END {print s}' "$work/time$n")
  err=$(python3 - "$work/run1000/measurements.csv" "$work/run$n/measurements.csv" <<'PY'
import csv, sys
def read(p):
    return {(r["speed_hz"], r["bearing"]): r for r in csv.DictReader(open(p))}
a, b = read(sys.argv[1]), read(sys.argv[2])
worst = 0.0
for bearing in {k[1] for k in a}:
    for ch in ("rel_y", "rel_z", "ped_y", "ped_z"):
        z = lambda r: complex(float(r[ch + "_re"]), float(r[ch + "_im"]))
        keys = [k for k in a if k[1] == bearing]
        peak = max(abs(z(a[k])) for k in keys)
        worst = max(worst, max(abs(z(a[k]) - z(b[k])) / peak for k in keys))
print(f"{worst:.1e}")
PY
)
  printf "%10d %10d %10.2f %10.2f %14.1f %14s\n" "$n" $((4 * (n + 1) + 4)) "$secs" "$cpu" "$(echo "$kb / 1024" | bc -l)" "$err"
done
