#!/bin/bash
# The accuracy budget's speed–error front on every bench scene (`mcdem bench --scene budget`, full
# size, two interleaved rounds): hydrogel deck (2 strokes of 30000 steps), dense periodic packing
# (N = 2048, 1500 steps), Lees–Edwards shear at phi = 0.8 (N = 500, 3000 steps after the
# compression), pour onto a floor (N = 384, 2500 steps). Writes front.txt (the table), front.json,
# front_stderr.txt (progress) and budget_<scene>.png next to this script, and the wall time.
# Usage: front.sh [MCDEM] (default target/release/mcdem, built with --features liggghts).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
mcdem=${1:-$root/target/release/mcdem}
start=$(date +%s)
"$mcdem" bench --scene budget --rounds 2 --plots "$here" --json "$here/front.json" \
  > "$here/front.txt" 2> "$here/front_stderr.txt"
end=$(date +%s)
# Keep the progress lines of each run, drop the progress bar's redraws.
tr '\r' '\n' < "$here/front_stderr.txt" | grep -a -v '^bench: \|^$' > "$here/front_stderr.tmp" || true
mv "$here/front_stderr.tmp" "$here/front_stderr.txt"
echo "wall time: $((end - start)) s ($(date -u +%Y-%m-%dT%H:%M:%SZ), $(nproc) cores shared, load: $(cut -d' ' -f1-3 /proc/loadavg))" >> "$here/front.txt"
cat "$here/front.txt"
