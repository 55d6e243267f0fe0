#!/usr/bin/env bash
# make lint: Verilator -Wall on every RTL module, then clang-tidy on the host
# library, the CLI and the twin (through the translation units that use it).
# usage: lint.sh <build-dir>
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-build}"
cd "$root"
scripts/lint_rtl.sh
test -f "$build/compile_commands.json" || cmake -S . -B "$build" >/dev/null
# Generated Verilator sources must exist for the TUs that include them.
cmake --build "$build" >/dev/null
files=$(ls host/*.cpp tests/test_pid_twin.cpp tests/test_pid_numerics.cpp tests/test_mul_align_rtl.cpp)
echo "clang-tidy: $(echo "$files" | wc -w) files"
clang-tidy -p "$build" --quiet $files 2>&1 | grep -v "warnings generated" || true
# Re-run for the exit status (grep above swallows it).
clang-tidy -p "$build" --quiet $files >/dev/null 2>&1
echo "lint: clean"
