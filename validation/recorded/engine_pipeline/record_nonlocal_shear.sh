#!/usr/bin/env bash
# Records the outputs of the nonlocal solver and of the shear study with one mcdem binary, for a
# byte-for-byte comparison of two builds (see README.md):
#   record_nonlocal_shear.sh BINARY OUTDIR
# Kept: the nonlocal die table with its per-step contacts, a 514-particle uniaxial compression (10
# load steps to φ ≈ 0.74), and a small shear study (N = 40, one μ and ν, six φ, two rates). Wall
# times (the `seconds` column of the nonlocal tables, the study's run and cost times) are removed
# before the files are kept.
set -euo pipefail
bin=$(realpath "$1")
out=$(realpath -m "$2")
root=$(cd "$(dirname "$0")/../../.." && pwd)
rm -rf "$out"
mkdir -p "$out/die_contacts"

# Drops the CSV column named `seconds` (comment lines kept as they are).
drop_seconds() {
    python3 -c '
import sys
rows = sys.stdin.read().splitlines()
col = None
for l in rows:
    if l.startswith("#") or not l:
        print(l); continue
    f = l.split(",")
    if col is None and "seconds" in f:
        col = f.index("seconds")
    if col is not None:
        del f[col]
    print(",".join(f))
'
}

"$bin" nonlocal "$root/validation/cases/nonlocal/die_single.json" -o "$out/die_raw.csv" \
    --contacts "$out/die_contacts" 2> /dev/null
drop_seconds < "$out/die_raw.csv" > "$out/die.csv"
rm "$out/die_raw.csv"

"$bin" uniaxial "$root/validation/cases/nonlocal/hydrogel_start_2nd_compression.dump" --nu 0.5 \
    --kernel boussinesq --steps 10 --z-end 0.14 -o "$out/uniaxial_raw.csv" 2> /dev/null
drop_seconds < "$out/uniaxial_raw.csv" > "$out/uniaxial.csv"
rm "$out/uniaxial_raw.csv"

study="$out/study_work"
# (stdout names the output directory: written as OUT.)
"$bin" study shear --grid quick --n 40 --mu 0.5 --nu 0.5 --no-cost --threads 2 --out "$study" \
    2> /dev/null | sed "s|$out|OUT|g" > "$out/study_stdout.txt"
# The per-run JSON files and the run table without their wall-time fields.
python3 - "$study" "$out" <<'PY'
import csv, json, os, sys
study, out = sys.argv[1], sys.argv[2]
timed = lambda k: "wall" in k or "seconds" in k or k.endswith("_s") or "per_s" in k
runs = sorted(os.listdir(os.path.join(study, "runs")))
with open(os.path.join(out, "study_runs.json"), "w") as f:
    for name in runs:
        d = json.load(open(os.path.join(study, "runs", name)))
        f.write(name + " " + json.dumps({k: v for k, v in d.items() if not timed(k)}, sort_keys=True) + "\n")
for name in ("runs.csv", "response_surface.csv"):
    p = os.path.join(study, name)
    if os.path.exists(p):
        rows = list(csv.reader(open(p)))
        keep = [i for i, k in enumerate(rows[0]) if not timed(k)]
        with open(os.path.join(out, "study_" + name), "w") as f:
            for r in rows:
                f.write(",".join(r[i] for i in keep) + "\n")
PY
rm -rf "$study"
echo "recorded $(find "$out" -type f | wc -l) files in $out"
