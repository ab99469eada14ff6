#!/bin/bash
# One-core cost of the Debian tutorials that run in both engines: stock LIGGGHTS against
# `mcdem run` (RAYON_NUM_THREADS=1), one after the other, each deck as shipped in a fresh copy of
# its directory. Prints user CPU seconds and wall seconds of each (user time is the steadier of
# the two on a shared machine).
# usage (from the repository root): validation/recorded/debian_decks/speed.sh [MCDEM]
SRC=/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public
BIN=$(realpath "${1:-target/release/mcdem}")
WORK=$(mktemp -d)
echo "| deck | LIGGGHTS user [s] | LIGGGHTS wall [s] | mcdem user [s] | mcdem wall [s] | LIGGGHTS / mcdem (user) |"
echo "|---|---|---|---|---|---|"
for deck in contactModels/in.newModels cohesion/in.noCohesion cohesion/in.cohesion \
            hysteresis/in.noHysteresis hysteresis/in.hysteresis conveyor/in.conveyor \
            insert_stream/in.insert_stream meshGran/in.meshGran mesh_tet/in.mesh_tet \
            movingMeshGran/in.movingMeshGran packing/in.packing; do
  for eng in lig mcdem; do
    d=$WORK/$eng/$(dirname $deck); mkdir -p $d; cp -r $SRC/$(dirname $deck)/. $d/; mkdir -p $d/post
    if [ $eng = lig ]; then
      ( cd $d && /usr/bin/time -f "%U %e" -o t.txt liggghts -in $(basename $deck) > log.txt 2>&1 )
    else
      ( cd $d && RAYON_NUM_THREADS=1 /usr/bin/time -f "%U %e" -o t.txt "$BIN" run $(basename $deck) --no-progress > log.txt 2>&1 )
    fi
  done
  read lu lw < $WORK/lig/$(dirname $deck)/t.txt
  read mu mw < $WORK/mcdem/$(dirname $deck)/t.txt
  echo "| ${deck} | $lu | $lw | $mu | $mw | $(echo "scale=2; $lu / $mu" | bc) |"
done
rm -rf "$WORK"
