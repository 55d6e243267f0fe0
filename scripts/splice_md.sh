#!/usr/bin/env bash
# Replace the lines between two marker lines of a file with a command's output.
# usage: splice_md.sh <file> <begin-marker> <end-marker> <command...>
set -euo pipefail
file="$1" begin="$2" end="$3"
shift 3
gen="$(mktemp)"
"$@" >"$gen"
awk -v b="$begin" -v e="$end" -v g="$gen" '
  $0 == b { print; while ((getline l < g) > 0) print l; skip = 1; next }
  $0 == e { skip = 0 }
  !skip { print }' "$file" >"$file.tmp"
mv "$file.tmp" "$file"
rm -f "$gen"
