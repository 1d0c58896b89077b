#!/usr/bin/env bash
# keys_docs_rewrite.sh ISOCHOR DOCS WORKDIR: `isochor keys --docs` on a copy of DOCS whose
# frames.rate row was edited by hand. With no room to write (a 1 KB file size limit) it stops
# with one line and leaves the copy byte for byte as it was, and no part file; with room it
# restores the row, so that the copy is DOCS again.
set -u
isochor=$1 docs=$2 work=$3
mkdir -p "$work"
copy=$work/scenes.md
sed 's/^| `frames.rate` | number > 0 |/| `frames.rate` | number |/' "$docs" > "$copy"
if cmp -s "$copy" "$docs"; then echo "the frames.rate row was not found in $docs"; exit 1; fi
before=$(cksum < "$copy")
err=$( (ulimit -f 1; "$isochor" keys --docs "$copy") 2>&1 >/dev/null); code=$?
[ $code -ne 0 ] || { echo "expected failure under a 1 KB file size limit, got exit 0"; exit 1; }
[ "$(printf '%s\n' "$err" | grep -c .)" -eq 1 ] || { echo "expected one line on stderr, got: $err"; exit 1; }
printf '%s\n' "$err" | grep -q "scenes.md: cannot be written" || { echo "unexpected message: $err"; exit 1; }
[ "$(cksum < "$copy")" = "$before" ] || { echo "the copy changed although the write failed"; exit 1; }
[ ! -e "$copy.part" ] || { echo "a part file was left: $copy.part"; exit 1; }
"$isochor" keys --docs "$copy" > /dev/null || { echo "the rewrite with room failed"; exit 1; }
cmp -s "$copy" "$docs" || { echo "the rewritten copy is not $docs"; exit 1; }
echo ok
