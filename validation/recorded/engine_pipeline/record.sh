#!/usr/bin/env bash
# Records the outputs of a set of engine decks with one mcdem binary, for a byte-for-byte
# comparison of two builds of the engine (see README.md):
#   record.sh BINARY OUTDIR
# Every deck runs on a rayon pool of 1 and of 2 threads (the latter with the threaded passes forced
# on), in a scratch copy of liggghts_inputs/. Kept: every file a deck writes (dumps, ave/time,
# print) and its stdout without the `Loop time` lines (wall-clock times).
set -euo pipefail
bin=$(realpath "$1")
out=$(realpath -m "$2")
root=$(cd "$(dirname "$0")/../../.." && pwd)
packing="$root/validation/cases/uniaxial/packing_514.data"
rm -rf "$out"
mkdir -p "$out"

# name  deck  extra arguments...
run() {
    local name=$1 deck=$2
    shift 2
    for t in 1 2; do
        local mode=serial
        [ "$t" = 2 ] && mode=parallel
        local work="$out/work_${name}_$t"
        rm -rf "$work"
        cp -r "$root/liggghts_inputs" "$work"
        mkdir -p "$work/post"
        (cd "$work" && RAYON_NUM_THREADS=$t "$bin" run "$deck" -log none --no-progress \
            --threads-mode "$mode" -var dir . "$@" | grep -v '^Loop time' > stdout.txt)
        # Keep only what the run wrote (the copied inputs are the same for both binaries).
        local dest="$out/${name}_$t"
        mkdir -p "$dest"
        (cd "$work" && find . -newer "$root/liggghts_inputs/hydrogel.in" -type f \
            \( -name '*.txt' -o -name '*.dump' -o -name '*.vtk' -o -name '*.data' \) \
            ! -path './meshes/*' -print0 | xargs -0 -r cp --parents -t "$dest")
        rm -rf "$work"
    done
}

for law in 0 1 2; do
    run "hydrogel_law$law" hydrogel.in -var law $law -var stroke 1000 -var strokes 2 -var every 10 \
        -var out piston.txt -var data "$packing"
done
run hydrogel_geomtol hydrogel.in -var law 0 -var stroke 1000 -var strokes 1 -var every 10 \
    -var out piston.txt -var data "$packing" --mc-geometry-tolerance 0.01 --mc-update-every 4
run shear_lees_edwards simple_shear_lees_edwards.in -var steps 2000 -var mu 0.3
for law in 0 1 2; do
    run "bcc_box_law$law" bcc_box.in -var law $law -var steps 1500 -var every 50
    run "single_particle_plates_law$law" single_particle_plates.in -var law $law -var steps 1500 -var every 50
    run "periodic_bcc_bed_law$law" periodic_bcc_bed.in -var law $law -var steps 2000 -var every 200
    run "three_sphere_stack_law$law" three_sphere_stack.in -var law $law -var steps 3000
    run "two_particles_law$law" two_particles.in -var law $law -var steps 2000
done
run plates_mesh particle_between_plates.in
run plates_mesh_mc particle_between_plates_mc.in
run plates_mesh_mc_advanced particle_between_plates_mc_advanced.in
run two_particle_collision two_particle_collision.in
run settle "$root/validation/cases/uniaxial/settle.in" -var dir "$root/liggghts_inputs" \
    -var loose "$packing" -var steps 2000 -var state settled.dump
echo "recorded $(find "$out" -type f | wc -l) files in $out"
