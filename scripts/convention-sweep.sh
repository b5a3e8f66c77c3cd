#!/usr/bin/env bash
# Convention-mistake sweep: two machines (the paper's, and a one-disk machine
# with tabulated cross-coupled bearings, tests/tests/identify_conventions.rs)
# x 6 data qualities (2, 3, 12 digits; 1 % and 3 % noise; 1 % noise at 3
# digits), each mistake made in the CSV text by scripts/convention_mistake.py;
# counts the pedestals whose mistake `plinth identify` names, and the clean
# pedestals it flags. PLINTH=<binary> uses that build instead of building one.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -n "${PLINTH:-}" ] || cargo build --release -q -p plinth
B="${PLINTH:-${CARGO_TARGET_DIR:-target}/release/plinth}"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
sed -n '/^const MACHINE_B: &str = r#"/,/^"#;/p' tests/tests/identify_conventions.rs | sed '1d;$d' > "$W/machine-b.toml"
tot=0; ok=0; clean=0; ctot=0
for mach in examples/feng-hahn-1997-damped.toml "$W/machine-b.toml"; do
  for cfg in "--digits 2" "--digits 3" "--digits 12" "--noise 0.01 --seed 3 --digits 6" "--noise 0.03 --seed 4 --digits 6" "--noise 0.01 --seed 5 --digits 3"; do
    rm -rf "$W/base"
    # shellcheck disable=SC2086
    "$B" simulate "$mach" --out "$W/base" --speeds 5:180:2.5 $cfg > /dev/null
    c=$("$B" identify "$W/base" --json 2> /dev/null | grep -c suspected_convention_error || true)
    ctot=$((ctot + 2)); clean=$((clean + c))
    [ "$c" -ne 0 ] && echo "clean data flagged: $(basename "$mach") $cfg"
    for m in conjugated swapped_yz rel_negated bearing_transposed cross_coupling_sign speed_in_rpm; do
      rm -rf "$W/mm"
      python3 scripts/convention_mistake.py "$W/base" "$W/mm" "$m"
      n=$("$B" identify "$W/mm" --json 2> /dev/null | grep -c "\"suspected_convention_error\": \"$m\"" || true)
      tot=$((tot + 2)); ok=$((ok + n))
      [ "$n" -ne 2 ] && echo "$(basename "$mach") $cfg $m: named at $n of 2 pedestals"
    done
  done
done
echo "named $ok of $tot mistaken pedestals; clean pedestals flagged: $clean of $ctot"
