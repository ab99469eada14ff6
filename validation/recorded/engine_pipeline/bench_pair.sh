#!/usr/bin/env bash
# Speed of two mcdem binaries side by side: `bench --quick` on the Rust-engine scenes (packing,
# hydrogel), alternating the binaries for R rounds, then per row the median over the rounds of
# the rate ratio (second binary / first) formed within each round (see docs/bench.md: only ratios
# of runs minutes apart mean something on a shared machine).
#   bench_pair.sh BEFORE AFTER OUTDIR [ROUNDS]
set -euo pipefail
a=$(realpath "$1")
b=$(realpath "$2")
out=$(realpath -m "$3")
rounds=${4:-3}
mkdir -p "$out"
for r in $(seq 1 "$rounds"); do
    for side in a b; do
        bin=$a
        [ "$side" = b ] && bin=$b
        "$bin" bench --quick --scene packing --scene hydrogel --json "$out/${side}_$r.json" > "$out/${side}_$r.txt"
    done
done
python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
def rows(path):
    d = json.load(open(path))
    return {(r['engine'], r['model'], r['scene'], r['n'], r['threads']): r['particle_steps_per_s']
            for r in d['rows'] if r['engine'] == 'rust'}
per = {}
for r in range(1, rounds + 1):
    ra, rb = rows(f'{out}/a_{r}.json'), rows(f'{out}/b_{r}.json')
    for k in ra.keys() & rb.keys():
        per.setdefault(k, []).append(rb[k] / ra[k])
print(f'{"scene":<10} {"model":<14} {"n":>7} {"thr":>3}  after/before rate: median [min, max] over {rounds} rounds')
for k in sorted(per):
    v = per[k]
    print(f'{k[2]:<10} {k[1]:<14} {k[3]:>7} {k[4]:>3}  {statistics.median(v):.3f} [{min(v):.3f}, {max(v):.3f}]')
allv = [statistics.median(v) for v in per.values()]
print(f'geometric mean of the medians: {statistics.geometric_mean(allv):.3f}')
PY
