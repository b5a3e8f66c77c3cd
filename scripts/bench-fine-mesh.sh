#!/usr/bin/env bash
# Fine meshes (issue 19): `plinth simulate` of the paper machine with its
# shaft cut into 10 000, 40 000 and 100 000 elements (196 speeds 5..200 Hz),
# each against the converged 1 000-element answer. Target: the last column
# (largest difference of any measured phasor, relative to that channel's
# peak over speed) at most 1e-6 at every size. Before the banded solve was
# refined (host/src/sim/refine.rs) it was 6.6e-6 / 6.6e-4 / 4.0e-4.
# The sweep and its table are scripts/bench-simulate-size.sh's.
# Usage: scripts/bench-fine-mesh.sh [ELEMENTS...]
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10000 40000 100000)
scripts/bench-simulate-size.sh "${sizes[@]}"
