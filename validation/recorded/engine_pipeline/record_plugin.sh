#!/usr/bin/env bash
# Records the outputs of the LIGGGHTS plugin (`mcdem-liggghts`) on decks under the three laws,
# for a byte-for-byte comparison of two builds (see README.md):
#   record_plugin.sh PLUGIN_BINARY OUTDIR
# Each deck runs in a scratch copy of liggghts_inputs/; kept: every file it writes (ave/time,
# dumps) and its screen output without the lines that carry wall-clock times.
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
    local work="$out/work_$name"
    cp -r "$root/liggghts_inputs" "$work"
    mkdir -p "$work/post"
    (cd "$work" && "$bin" -in "$deck" -log none -var dir . "$@" \
        | grep -a -v -E -e '^Loop time|Performance:|CPU use|Total wall time|^Memory usage' \
            -e '^(Pair|Neigh|Comm|Output|Modify|Other) +\|' \
            -e 'time \(%\) =|^Setting up run at|Nlocal:|Nghost:|Neighs:|Histogram|Neighbor list builds|Dangerous builds|Ave neighs|Total # of neighbors' > stdout.txt)
    local dest="$out/$name"
    mkdir -p "$dest"
    (cd "$work" && find . -newer "$root/liggghts_inputs/hydrogel.in" -type f \
        \( -name '*.txt' -o -name '*.dump' -o -name '*.vtk' \) ! -path './meshes/*' -print0 \
        | xargs -0 -r cp --parents -t "$dest")
    rm -rf "$work"
}

for law in 0 1 2; do
    run "hydrogel_law$law" hydrogel.in -var law $law -var stroke 1000 -var strokes 2 -var every 10 \
        -var out piston.txt -var data "$packing"
    run "bcc_box_law$law" bcc_box.in -var law $law -var steps 1500 -var every 50
    run "single_particle_plates_law$law" single_particle_plates.in -var law $law -var steps 1500 -var every 50
done
run hydrogel_approx hydrogel.in -var law 0 -var stroke 1000 -var strokes 1 -var every 10 \
    -var out piston.txt -var data "$packing" -var geomtol 0.01 -var mcevery 4
echo "recorded $(find "$out" -type f | wc -l) files in $out"
