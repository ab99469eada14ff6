#!/usr/bin/env bash
# Wall time of the 514-particle hydrogel deck (liggghts_inputs/hydrogel.in, two compression cycles)
# on 1 and 2 MPI ranks, with `mc_advanced` (the plugin) and with stock `hertz`, run back to back in
# one invocation so that all four runs see the same machine; prints the times and the ratios.
# The ranks split the box in x (the deck's default grid `* 1 1`, the Debian example's): split in
# height (`-var pz 2`) one rank would hold nearly all of the packing, which fills the lower 40 % of
# the box, and a second rank would gain nothing.
# Usage: benches/hydrogel_mpi.sh [STEPS_PER_STROKE (default 30000, the example's)]
set -euo pipefail
ROOT=$(realpath "$(dirname "$0")/..")
BIN=$ROOT/target/release/mcdem-liggghts
[ -x "$BIN" ] || { echo "build the plugin first: cargo build --release --features liggghts" >&2; exit 2; }
STROKE=${1:-30000}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
declare -A T
for law in 0 1; do
  for np in 1 2; do
    start=$(date +%s.%N)
    OMPI_MCA_mpi_yield_when_idle=1 mpirun --allow-run-as-root --oversubscribe --bind-to none -np $np "$BIN" \
      -in "$ROOT/liggghts_inputs/hydrogel.in" -var dir "$ROOT/liggghts_inputs" -var law $law \
      -var stroke "$STROKE" -var out "f$law$np.txt" -log "log$law$np" > /dev/null
    T[$law$np]=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
  done
done
awk -v m1="${T[01]}" -v m2="${T[02]}" -v h1="${T[11]}" -v h2="${T[12]}" 'BEGIN {
  printf "%-12s %10s %11s %8s\n", "model", "1 rank [s]", "2 ranks [s]", "speedup"
  printf "%-12s %10.1f %11.1f %8.2f\n", "mc_advanced", m1, m2, m1 / m2
  printf "%-12s %10.1f %11.1f %8.2f\n", "hertz", h1, h2, h1 / h2
  printf "mc_advanced / hertz: %.2f (1 rank), %.2f (2 ranks)\n", m1 / h1, m2 / h2
}'
