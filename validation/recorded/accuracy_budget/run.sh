#!/bin/bash
# Accuracy budget of the multi-contact corrections (`--mc-accuracy EPS`) against the exact pass and
# the fixed approximations, on the hydrogel compression (liggghts_inputs/hydrogel.in, the deck
# `mcdem bench` runs): the example's piston speed (stroke 30000 steps), compression and release
# (strokes 2, 60000 steps), one thread. All settings interleaved, two rounds; the table takes the
# median (of two: the mean) user time. The piston-force error is max |F - F_exact| over the curve
# divided by the exact curve's range (as `mcdem bench`). A third, untimed pass of each budgeted
# setting runs the shadow check every 100 steps: the measured radius-change error next to its bound.
# Usage: run.sh [MCDEM] (default target/release/mcdem); writes results.md next to this script.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
mcdem=${1:-$root/target/release/mcdem}
decks=$root/liggghts_inputs
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export RAYON_NUM_THREADS=1
settings=("hertz|-var law 1" "exact|-var law 0" "EPS 1e-2|-var law 0 --mc-accuracy 1e-2"
  "EPS 1e-3|-var law 0 --mc-accuracy 1e-3" "EPS 1e-4|-var law 0 --mc-accuracy 1e-4"
  "geometryTolerance 1e-3 updateEvery 10|-var law 0 --mc-geometry-tolerance 1e-3 --mc-update-every 10"
  "geometryTolerance 1e-4|-var law 0 --mc-geometry-tolerance 1e-4")
run() { # index round extra-args...
  local k=$1 r=$2; shift 2
  local args=${settings[$k]#*|}
  ( cd "$work" && /usr/bin/time -f "%U" -o "time_${k}_$r" "$mcdem" run "$decks/hydrogel.in" \
      -var stroke 30000 -var strokes 2 -var every 100 -var dir "$decks" -var out "force_${k}_$r.txt" \
      -log none --no-progress --threads-mode serial $args "$@" > "out_${k}_$r" )
}
for r in 1 2; do
  for k in "${!settings[@]}"; do run "$k" "$r"; echo "round $r: ${settings[$k]%%|*}: $(cat "$work/time_${k}_$r") s" >&2; done
done
for k in 2 3 4; do run "$k" check --mc-accuracy-check 100; done
col() { awk '!/^#/ {print $4}' "$1"; }
err() { # force error of file $1 against the exact run
  paste <(col "$work/force_1_1.txt") <(col "$1") | awk '
    NR==1 {lo=$1; hi=$1} {if ($1<lo) lo=$1; if ($1>hi) hi=$1; d=$1-$2; if (d<0) d=-d; if (d>m) m=d}
    END {printf "%.2e", m/(hi-lo)}'
}
med() { echo "($(cat "$work/time_${1}_1") + $(cat "$work/time_${1}_2")) / 2" | bc -l; }
hertz=$(med 0)
{
  echo "Command: validation/recorded/accuracy_budget/run.sh ($(date -u +%Y-%m-%d), $(nproc) cores shared with other builds)"
  echo
  echo "| setting | user time [s] (rounds 1, 2) | cost vs Hertz | piston-force error / range | Eq. 2 recomputed | shadow check: measured / bound (of the particle's scale) |"
  echo "|---|---|---|---|---|---|"
  for k in "${!settings[@]}"; do
    name=${settings[$k]%%|*}
    t=$(med "$k")
    e=$([ "$k" = 0 ] && echo "-" || err "$work/force_${k}_1.txt")
    rec=$(grep -o 'recomputed in [0-9.]* %' "$work/out_${k}_1" | awk '{s+=$3; n++} END {if (n) printf "%.1f %% (mean of %d runs)", s/n, n}' || true)
    chk="-"
    if [ -f "$work/out_${k}_check" ]; then
      chk=$(grep -o 'measured error [0-9.e+-]*, bound [0-9.e+-]*' "$work/out_${k}_check" | awk '{m=$3; b=$5; sub(",","",m); print m " / " b}' | sort -g -t/ -k1 | tail -1)
    fi
    printf "| %s | %.2f (%s, %s) | %.2f | %s | %s | %s |\n" "$name" "$t" "$(cat "$work/time_${k}_1")" \
      "$(cat "$work/time_${k}_2")" "$(echo "$t / $hertz" | bc -l)" "$e" "${rec:--}" "$chk"
  done
} > "$here/results.md"
cat "$here/results.md"
