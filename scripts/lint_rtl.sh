#!/usr/bin/env bash
# verilator --lint-only -Wall on every rtl/ module, each as its own top, and
# on rtl/ as a whole (the way a newcomer would first run it).
set -euo pipefail
cd "$(dirname "$0")/../rtl"
status=0
for f in *.v; do
  top="${f%.v}"
  if ! verilator --lint-only -Wall -I. --top-module "$top" *.v; then
    echo "lint failed: rtl/$f" >&2
    status=1
  fi
done
if ! verilator --lint-only -Wall -I. *.v; then
  echo "lint failed: rtl/ as a whole" >&2
  status=1
fi
[ $status -eq 0 ] && echo "rtl lint: $(ls *.v | wc -l) modules clean"
exit $status
