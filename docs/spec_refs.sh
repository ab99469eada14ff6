#!/bin/sh
# Rewrites the references to the specification, written `SPEC §N` in comments, docs and data
# headers, into `docs/spec.md §N` (the specification in this repository), then checks that every
# section cited exists as a heading of docs/spec.md. Idempotent: a second run changes nothing.
#
#   docs/spec_refs.sh [REPO]        rewrite the tracked files of REPO (default: this checkout)
#   docs/spec_refs.sh --check REPO  only list the cited sections and check them (no rewrite)
#
# `SPEC §5 item N` becomes `docs/spec.md §5.N` (the scenes are numbered §5.1–§5.3 there). A few
# references without a section number are rewritten phrase by phrase below. Recorded runs
# (validation/recorded/) are rewritten too: their text names the specification like the code did.
set -eu

check_only=0
if [ "${1:-}" = "--check" ]; then
    check_only=1
    shift
fi
repo=${1:-$(dirname "$0")/..}
cd "$repo"
spec=docs/spec.md
[ -f "$spec" ] || { echo "no $spec in $repo" >&2; exit 1; }

# Tracked text files that mention SPEC, except the specification and this script.
files=$(git ls-files -z | xargs -0 grep -Il 'SPEC' -- 2>/dev/null | grep -v -e '^docs/spec\.md$' -e '^docs/spec_refs\.sh$' || true)

if [ "$check_only" = 0 ] && [ -n "$files" ]; then
    # One sed program, GNU sed (-i, \b). Order matters: the `item` form before the general one.
    echo "$files" | while IFS= read -r f; do
        sed -i \
            -e 's/\bSPEC §5 item \([0-9]\)/docs\/spec.md §5.\1/g' \
            -e 's/\bSPEC §/docs\/spec.md §/g' \
            -e 's/the SPEC relation/the relation of docs\/spec.md §4/g' \
            -e 's/The SPEC digits/The digits quoted in docs\/spec.md §4.1/g' \
            -e 's/SPEC φ table/φ table of docs\/spec.md §5.2/g' \
            -e 's/vs SPEC {spec}/vs docs\/spec.md §4.1 {spec}/g' \
            "$f"
        done
fi

# Every section cited (`docs/spec.md §N` or, before the rewrite, `SPEC §N`, and a bare `§N` that follows one in the same list, as
# in `§4, §4.1`) must be a heading `## N.` or `### N ` of the specification.
cited=$(git ls-files -z | xargs -0 grep -Iho '\(docs/spec\.md\|SPEC\) §[0-9][0-9.]*\(, §[0-9][0-9.]*\)*' -- 2>/dev/null |
    grep -o '§[0-9][0-9.]*' | sed 's/^§//; s/\.$//' | sort -u -V)
status=0
for s in $cited; do
    if grep -Eq "^#{2,3} $(echo "$s" | sed 's/\./\\./g')(\.| )" "$spec"; then
        echo "§$s ok"
    else
        echo "§$s MISSING from $spec" >&2
        status=1
    fi
done
left=$(git ls-files -z | xargs -0 grep -In '\bSPEC\b' -- 2>/dev/null | grep -v -e '^docs/spec_refs\.sh:' || true)
if [ -n "$left" ]; then
    echo "references to SPEC left:" >&2
    echo "$left" >&2
    [ "$check_only" = 1 ] || status=1
fi
exit $status
