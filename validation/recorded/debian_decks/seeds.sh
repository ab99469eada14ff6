#!/bin/bash
# Six insert/pack seeds of the two tutorials whose bed heights differed most between the engines
# on two seeds, in stock LIGGGHTS and in mcdem run, one run after the other on one core each.
# usage (from the repository root): validation/recorded/debian_decks/seeds.sh [MCDEM]
# (runs in $OUT, default /tmp/seeds; then: python3 validation/recorded/debian_decks/seeds_stats.py)
SRC=/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public
BIN=${1:-target/release/mcdem}; BIN=$(realpath "$BIN")
for deck in contactModels/in.newModels cohesion/in.cohesion; do
  for seed in 32452843 67867967 86028121 49979687 32452867 67867979; do
    for eng in lig mcdem; do
      d=${OUT:-/tmp/seeds}/$(basename $deck)_${seed}_$eng; rm -rf $d; mkdir -p $d; cp -r $SRC/$(dirname $deck)/. $d/; mkdir -p $d/post
      sed -i "s/insert\/pack seed 32452843/insert\/pack seed $seed/" $d/$(basename $deck)
      s=$(date +%s.%N)
      if [ $eng = lig ]; then (cd $d && liggghts -in $(basename $deck) > log.txt 2>&1); else (cd $d && RAYON_NUM_THREADS=1 $BIN run $(basename $deck) --no-progress > log.txt 2>&1); fi
      echo "$deck $seed $eng rc=$? $(echo "$(date +%s.%N) - $s" | bc)" >> ${OUT:-/tmp/seeds}/times.txt
    done
  done
done
