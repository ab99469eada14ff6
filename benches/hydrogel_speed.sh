#!/usr/bin/env bash
# Speed of `mcdem run` next to stock LIGGGHTS on the hydrogel example (514 particles, Hertz,
# 4 strokes × 30000 steps), VTK dumps off in both, run back to back in one invocation so both see
# the same machine load. Prints particle-steps per second from each engine's "Loop time" lines,
# LIGGGHTS on one and (with mpirun) two MPI ranks, mcdem with one and with two threads.
# Usage: benches/hydrogel_speed.sh [path/to/mcdem]
set -euo pipefail
MCDEM=${1:-$(dirname "$0")/../target/release/mcdem}
MCDEM=$(realpath "$MCDEM")
EX=/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/hydrogel_multicontact
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cp -r "$EX/data" "$EX/meshes" "$W/"
mkdir -p "$W/post"
sed '/^dump/d' "$EX/in.hydrogel_default" > "$W/in.hydrogel_default"
cd "$W"
rate() { # sum steps and seconds over "Loop time of T on P procs for N steps with A atoms" lines
  awk '/^Loop time of/ {t+=$4; n+=$9; a=$12} END {printf "%.4g s, %.4g particle-steps/s\n", t, n*a/t}'
}
liggghts -in in.hydrogel_default -log log.liggghts > /dev/null 2>&1
L=$(rate < log.liggghts)
L2=
# Two ranks as `mcdem bench` runs them (src/bench/hydrogel.rs); skipped if mpirun fails.
if command -v mpirun > /dev/null \
  && OMPI_MCA_mpi_yield_when_idle=1 mpirun --allow-run-as-root --oversubscribe --bind-to none -np 2 \
    liggghts -in in.hydrogel_default -log log.liggghts2 > /dev/null 2>&1; then
  L2=$(rate < log.liggghts2)
fi
RAYON_NUM_THREADS=1 "$MCDEM" run in.hydrogel_default -log log.mcdem1 --no-progress > /dev/null
M1=$(rate < log.mcdem1)
RAYON_NUM_THREADS=2 "$MCDEM" run in.hydrogel_default -log log.mcdem2 --no-progress > /dev/null
M2=$(rate < log.mcdem2)
echo "LIGGGHTS (1 rank):   $L"
[ -n "$L2" ] && echo "LIGGGHTS (2 ranks):  $L2"
echo "mcdem (1 thread):    $M1"
echo "mcdem (2 threads):   $M2"
python3 - "$L" "$M1" "$M2" "$L2" <<'PY'
import sys
r = [float(a.split(",")[1].split()[0]) for a in sys.argv[1:4]]
print(f"ratio mcdem/LIGGGHTS 1 rank: 1 thread {r[1]/r[0]:.2f}, 2 threads {r[2]/r[0]:.2f}")
if sys.argv[4]:
    l2 = float(sys.argv[4].split(",")[1].split()[0])
    print(f"ratio mcdem 2 threads / LIGGGHTS 2 ranks: {r[2]/l2:.2f}; LIGGGHTS 2 ranks / 1 rank: {l2/r[0]:.2f}")
PY
