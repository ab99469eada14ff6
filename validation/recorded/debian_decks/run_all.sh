#!/bin/bash
# Runs every example deck of Debian's liggghts-doc through `mcdem run` and prints a Markdown table
# row per deck: whether it ran to its end, stopped with an error (the first ERROR line), or was
# still running at the time cap (seconds, first argument, default 60). The decks of one tutorial
# directory run one after the other, in name order, in one copy of it, as a user runs them: so
# `in.insert_stream_reset_timestep` reads the restart that `in.insert_stream` wrote.
# usage: validation/recorded/debian_decks/run_all.sh [CAP_S] [MCDEM]
CAP=${1:-60}
BIN=$(realpath "${2:-target/release/mcdem}")
SRC=/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public
WORK=$(mktemp -d)
echo "| deck | result |"
echo "|---|---|"
for deck in $(cd "$SRC" && find . -name 'in.*' | sort); do
  dir=$WORK/$(dirname "$deck")
  [ -d "$dir" ] || { mkdir -p "$dir"; cp -r "$SRC/$(dirname "$deck")"/. "$dir"/; }
  ( cd "$dir" && timeout "$CAP" "$BIN" run "$(basename "$deck")" --log none --no-progress > out.txt 2>&1; echo $? > rc.txt )
  rc=$(cat "$dir/rc.txt")
  if [ "$rc" = 0 ]; then r="runs to its end"
  elif [ "$rc" = 124 ]; then r="still running at the ${CAP} s cap (no error)"
  else r="stops: \`$(grep -m1 'ERROR' "$dir/out.txt" | sed 's/|/\\|/g')\`"; fi
  echo "| ${deck#./} | $r |"
done
rm -rf "$WORK"
