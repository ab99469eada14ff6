#!/bin/sh
# Records the walls-on-points runs: RAYON_NUM_THREADS=1, user CPU and wall time into wall_times.txt.
# Usage (from this directory): sh run_all.sh MCDEM_BINARY NAME...
bin=$1; shift
for n in "$@"; do
  out=/tmp/pw_rec/$n
  rm -rf "$out"; mkdir -p "$out"
  /usr/bin/time -f "$n %e s wall %U s CPU" -o "$out/time.txt" env RAYON_NUM_THREADS=1 "$bin" mpm "$n.json" --out "$out" > "$out/log.txt" 2>&1
  cat "$out/time.txt" >> wall_times.txt
  mkdir -p "$n"
  for f in history.csv packing.csv bodies.csv points.csv stress_strain.png force_displacement.png points_final.png log.txt; do
    [ -f "$out/$f" ] && cp "$out/$f" "$n/"
  done
  grep -v "running steps" "$n/log.txt" > "$n/log.tmp" && mv "$n/log.tmp" "$n/log.txt"
done
