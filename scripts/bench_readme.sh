#!/usr/bin/env bash
# Copy the benchmark table of build/bench/report.md (`make bench` writes it)
# into README.md, between its markers, so that the README shows the numbers
# of the last full run and nothing typed by hand.
# usage: bench_readme.sh [report.md] [README.md]
set -euo pipefail
report="${1:-build/bench/report.md}" readme="${2:-README.md}"
[ -f "$report" ] || { echo "bench_readme.sh: no $report: run 'make bench' first" >&2; exit 1; }
if grep -q 'Quick run' "$report"; then
  echo "bench_readme.sh: $report is a quick run: run the full 'make bench'" >&2
  exit 1
fi
grep -qx '<!-- README table -->' "$report" ||
  { echo "bench_readme.sh: $report has no README table (the circle with tuned gains)" >&2; exit 1; }
here="$(dirname "$0")"
"$here/splice_md.sh" "$readme" "<!-- GENERATED from build/bench/report.md: make readme-bench -->" \
  "<!-- end of generated table -->" \
  sed -n '/^<!-- README table -->$/,/^<!-- end of README table -->$/{//!p}' "$report"
