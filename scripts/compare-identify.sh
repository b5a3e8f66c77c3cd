#!/usr/bin/env bash
# Compares two plinth builds byte for byte on identify --json (ML and OLS),
# identify on a measured and an unmeasured base, diagnose --json and a short
# accuracy table, over runs that take every noise source: full-precision
# noise (scatter), 3 and 12 digits (digits; truncated digits), the noise
# columns, a heteroscedastic noise (sd ∝ |phasor|), on two machines, and
# the six convention mistakes of scripts/convention_mistake.py made in three
# of them (the convention check's findings). For
# refactors that must not change a number (issue 19, "one engine").
# Stdout, stderr and the exit code are compared. With HOSTILE=1 the hostile
# inputs are compared instead (scripts/hostile_inputs.py: one number of
# either table replaced by text a reader may meet, whole files broken).
#   [HOSTILE=1] scripts/compare-identify.sh OLD_PLINTH NEW_PLINTH
# Prints one line per case (same / DIFFERENT) and exits 1 on any difference.
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1
new=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
damped=examples/feng-hahn-1997-damped.toml
skid=examples/two-pedestals-on-skid.toml

status=0
compare() {
  local name=$1
  shift
  local code=0
  "$old" "$@" >"$work/old.out" 2>"$work/old.err" || code=$?
  echo "exit $code" >>"$work/old.err"
  code=0
  "$new" "$@" >"$work/new.out" 2>"$work/new.err" || code=$?
  echo "exit $code" >>"$work/new.err"
  if cmp -s "$work/old.out" "$work/new.out" && cmp -s "$work/old.err" "$work/new.err"; then
    printf "same       %s (%s bytes)\n" "$name" "$(wc -c <"$work/new.out")"
  else
    printf "DIFFERENT  %s\n" "$name"
    diff "$work/old.out" "$work/new.out" | head -8 || true
    status=1
  fi
}

if [ "${HOSTILE:-0}" = 1 ]; then
  "$old" simulate "$damped" --speeds 5:200:5 --noise 0.01 --out "$work/base" >/dev/null
  python3 scripts/hostile_inputs.py "$work/base" "$work/hostile"
  runs=0
  for dir in "$work"/hostile/*/; do
    runs=$((runs + 1))
    for est in ml ols; do
      compare "identify hostile $(basename "$dir") $est" identify "${dir%/}" --json --estimator "$est"
    done
  done
  echo "identify compared on $runs hostile runs × 2 estimators"
  exit $status
fi

"$old" simulate "$damped" --speeds 5:200:1 --noise 0.01 --out "$work/noise" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --digits 3 --out "$work/digits3" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --digits 3 --truncate --out "$work/trunc3" >/dev/null
"$old" simulate "$damped" --speeds 5:200:2 --digits 12 --out "$work/digits12" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --noise 0.002 --seed 4 --out "$work/noise_digits12" >/dev/null
"$old" simulate "$skid" --speeds 5:200:1 --noise 0.01 --seed 2 --out "$work/skid" >/dev/null
"$old" simulate "$skid" --speeds 5:200:1 --digits 4 --out "$work/skid_digits4" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --out "$work/clean" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --noise 0.005 --seed 7 --digits 2 --out "$work/digits2" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --digits 2 --truncate --out "$work/trunc2" >/dev/null
"$old" simulate "$damped" --speeds 5:200:1 --noise 0.003 --seed 11 --digits 6 --out "$work/digits6" >/dev/null
"$old" simulate "$skid" --speeds 5:200:1 --digits 2 --out "$work/skid_digits2" >/dev/null
# The skid runs without their base.csv: the base not measured.
for run in skid skid_digits4; do
  mkdir "$work/${run}_unmeasured"
  cp "$work/$run"/{measurements.csv,bearings.csv} "$work/${run}_unmeasured/"
done
python3 - "$work" <<'EOF'
import csv, math, os, random, shutil, sys
work = sys.argv[1]
random.seed(19)
def rows(run):
    with open(os.path.join(work, run, "measurements.csv")) as f:
        return list(csv.reader(f))
def write(run, table):
    os.makedirs(os.path.join(work, run), exist_ok=True)
    for name in ("bearings.csv", "truth.json"):
        src = os.path.join(work, "clean", name)
        if os.path.exists(src):
            shutil.copy(src, os.path.join(work, run, name))
    with open(os.path.join(work, run, "measurements.csv"), "w", newline="") as f:
        csv.writer(f).writerows(table)
clean = rows("clean")
head, body = clean[0], clean[1:]
# Heteroscedastic: complex noise of 1 % of each phasor's own magnitude.
het = [head]
# Noise columns: 0.5 % of each channel's RMS, written as *_sd and drawn with it.
cols = [head + ["rel_y_sd", "rel_z_sd", "ped_y_sd", "ped_z_sd"]]
rms = {}
for r in body:
    for ch in range(4):
        z = complex(float(r[2 + 2 * ch]), float(r[3 + 2 * ch]))
        rms.setdefault((r[1], ch), []).append(abs(z) ** 2)
rms = {k: math.sqrt(sum(v) / len(v)) for k, v in rms.items()}
for r in body:
    h, c = r[:2], r[:2]
    sds = []
    for ch in range(4):
        z = complex(float(r[2 + 2 * ch]), float(r[3 + 2 * ch]))
        s = 0.01 * abs(z) / math.sqrt(2)
        n = complex(random.gauss(0, s), random.gauss(0, s))
        h += [repr((z + n).real), repr((z + n).imag)]
        sd = 0.005 * rms[(r[1], ch)]
        n = complex(random.gauss(0, sd / math.sqrt(2)), random.gauss(0, sd / math.sqrt(2)))
        c += [repr((z + n).real), repr((z + n).imag)]
        sds.append(repr(sd))
    het.append(h)
    cols.append(c + sds)
write("hetero", het)
write("columns", cols)
EOF

# Each convention mistake made in the text (scripts/convention_mistake.py)
# of a noisy, a 3-digit and a skid run: the convention check's findings.
mistakes="conjugated swapped_yz rel_negated bearing_transposed cross_coupling_sign speed_in_rpm"
for run in noise digits3 skid digits12 hetero columns; do
  for mistake in $mistakes; do
    python3 scripts/convention_mistake.py "$work/$run" "$work/${run}_$mistake" "$mistake"
  done
done

runs=0
for run in noise digits3 trunc3 digits12 noise_digits12 hetero columns skid skid_digits4 clean \
  digits2 trunc2 digits6 skid_digits2; do
  runs=$((runs + 1))
  for est in ml ols; do
    compare "identify $run $est" identify "$work/$run" --json --estimator "$est"
  done
done
# Every stored run of the four unseen machines (ROSS: clean, outliers,
# keyphasor flips, sub-bases, runout, delays, cross terms, tables).
for dir in tests/data/ross-unseen*/*/; do
  [ -f "$dir/measurements.csv" ] || continue
  runs=$((runs + 1))
  for est in ml ols; do
    compare "identify ${dir%/} $est" identify "${dir%/}" --json --estimator "$est"
  done
done
for run in noise digits3 skid digits12 hetero columns; do
  runs=$((runs + 6))
  for mistake in $mistakes; do
    for est in ml ols; do
      compare "identify ${run}_$mistake $est" identify "$work/${run}_$mistake" --json --estimator "$est"
    done
  done
done
compare "identify trunc3_rel_negated ml --truncated" identify "$work/digits3_rel_negated" --json --truncated
compare "identify trunc3 ml --truncated" identify "$work/trunc3" --json --truncated
compare "identify noise ml --compare-ols" identify "$work/noise" --json --compare-ols
compare "identify skid --unmeasured-base" identify "$work/skid_unmeasured" --json --unmeasured-base left,right
compare "identify skid_digits4 --unmeasured-base" identify "$work/skid_digits4_unmeasured" --json --unmeasured-base left,right
for run in noise digits3 columns hetero; do
  compare "diagnose $run" diagnose "$work/$run" --machine "$damped" --json --quiet
done
compare "accuracy noise" accuracy "$damped" --noise 0.01 --draws 8 --json --quiet
compare "accuracy digits" accuracy "$damped" --digits 3 --draws 8 --json --quiet
echo "identify compared on $runs runs × 2 estimators"
exit $status
