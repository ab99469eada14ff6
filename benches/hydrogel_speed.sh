#!/usr/bin/env bash
# Speed of `mcdem run` next to stock LIGGGHTS on the hydrogel example (514 particles, Hertz,
# 4 strokes × 30000 steps), VTK dumps off in both, run back to back in one invocation so both see
# the same machine load. Prints particle-steps per second from each engine's "Loop time" lines.
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
"$MCDEM" run in.hydrogel_default -log log.mcdem --no-progress > /dev/null
M=$(rate < log.mcdem)
echo "LIGGGHTS: $L"
echo "mcdem:    $M"
python3 - "$L" "$M" <<'PY'
import sys
l = float(sys.argv[1].split(",")[1].split()[0]); m = float(sys.argv[2].split(",")[1].split()[0])
print(f"ratio mcdem/LIGGGHTS: {m/l:.2f}")
PY
