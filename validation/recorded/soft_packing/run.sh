#!/bin/bash
# Runs liggghts_inputs/soft_packing.in in both engines with two insertion seeds and compares the
# piston curves (force on the piston against its height) with `mcdem compare` and by NRMSE.
# usage (from the repository root, after `cargo build --release --features liggghts`):
#   validation/recorded/soft_packing/run.sh
set -euo pipefail
ROOT=$(pwd)
WORK=$(mktemp -d)
cp liggghts_inputs/soft_packing.in "$WORK"/
mkdir -p "$WORK/meshes" "$WORK/post"
cp liggghts_inputs/meshes/piston_square.stl "$WORK/meshes/"
cd "$WORK"
for seed in 32452867 67867967; do
  s=$(date +%s.%N)
  RAYON_NUM_THREADS=1 "$ROOT/target/release/mcdem" run soft_packing.in --no-progress \
    --var seed $seed --var out post/mcdem_$seed.txt > mcdem_$seed.log 2>&1
  echo "mcdem seed $seed: $(echo "$(date +%s.%N) - $s" | bc) s"
  s=$(date +%s.%N)
  "$ROOT/target/release/mcdem-liggghts" -in soft_packing.in -var seed $seed \
    -var out post/liggghts_$seed.txt > liggghts_$seed.log 2>&1
  echo "LIGGGHTS seed $seed: $(echo "$(date +%s.%N) - $s" | bc) s"
done
for pair in "mcdem_32452867 liggghts_32452867" "mcdem_67867967 liggghts_67867967" \
            "liggghts_32452867 liggghts_67867967" "mcdem_32452867 mcdem_67867967"; do
  set -- $pair
  echo "== $1 against $2"
  "$ROOT/target/release/mcdem" compare post/$1.txt post/$2.txt --tol 1 || true
  python3 - post/$1.txt post/$2.txt <<'PY'
import sys
def rd(f):
    return [list(map(float, l.split())) for l in open(f) if l.strip() and not l.startswith('#')]
a, b = rd(sys.argv[1]), rd(sys.argv[2])
# NRMSE of the force over the compaction (piston below 0.11 m, solid fraction above 0.55),
# relative to the mean force of the second file there.
pts = [(x[2], y[2]) for x, y in zip(a, b) if x[1] < 0.11]
rmse = (sum((p - q) ** 2 for p, q in pts) / len(pts)) ** 0.5
mean = sum(q for _, q in pts) / len(pts)
print(f"NRMSE over {len(pts)} points (piston below 0.11 m): {rmse / mean:.4f}; final force {a[-1][2]:.3f} N against {b[-1][2]:.3f} N")
PY
done
rm -rf "$WORK"
