#!/usr/bin/env bash
# Speed of `mcdem run` next to stock LIGGGHTS on the hydrogel example (514 particles, Hertz,
# 4 strokes × 30000 steps), VTK dumps off in both, run back to back in one invocation so both see
# the same machine load. Prints particle-steps per second from each engine's "Loop time" lines,
# mcdem with one and with two threads (the deck is too small for LIGGGHTS to gain from a second
# MPI rank: 16.9 s on 2 ranks against 15.7 s on 1, benches/hydrogel_mpi.sh).
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
RAYON_NUM_THREADS=1 "$MCDEM" run in.hydrogel_default -log log.mcdem1 --no-progress > /dev/null
M1=$(rate < log.mcdem1)
RAYON_NUM_THREADS=2 "$MCDEM" run in.hydrogel_default -log log.mcdem2 --no-progress > /dev/null
M2=$(rate < log.mcdem2)
echo "LIGGGHTS (1 rank):   $L"
echo "mcdem (1 thread):    $M1"
echo "mcdem (2 threads):   $M2"
python3 - "$L" "$M1" "$M2" <<'PY'
import sys
r = [float(a.split(",")[1].split()[0]) for a in sys.argv[1:]]
print(f"ratio mcdem/LIGGGHTS: 1 thread {r[1]/r[0]:.2f}, 2 threads {r[2]/r[0]:.2f}")
PY
