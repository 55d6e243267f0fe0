#!/usr/bin/env bash
# make lint: Verilator -Wall on every RTL module, then clang-tidy on the host
# library, the CLI, the plant models and the twin (through the translation units
# that use it).
# usage: lint.sh <build-dir>
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-build}"
cd "$root"
scripts/lint_rtl.sh
# The same build directory make test uses (CI lints first, then tests it).
gen=""
command -v ninja >/dev/null 2>&1 && gen="-G Ninja"
test -f "$build/compile_commands.json" || cmake -S . -B "$build" $gen >/dev/null
# Generated Verilator sources must exist for the TUs that include them.
cmake --build "$build" -j "$(nproc)" >/dev/null
files=$(ls host/*/*.cpp sim/*/*.cpp tests/test_layers.cpp tests/test_sim_plant.cpp tests/test_sim_config.cpp tests/test_pid_twin.cpp \
  tests/test_pid_numerics.cpp tests/test_mul_align_rtl.cpp tests/test_cosim.cpp tests/test_motion_core_twin.cpp \
  tests/test_interp_twin.cpp tests/test_interp_rtl.cpp tests/test_motion_core_rtl.cpp \
  tests/test_quad_decoder_twin.cpp tests/test_quad_decoder_rtl.cpp tests/test_quad_rate_rtl.cpp \
  tests/test_board_link.cpp tests/test_cli_board.cpp tests/test_cli_step.cpp tests/test_board_capture.cpp tests/test_board_rx.cpp \
  tests/test_vboard_io.cpp tests/test_vboard_mpg.cpp tests/test_cli_mpg.cpp tests/test_board_setup.cpp tests/test_board_builds.cpp tests/test_cycles.cpp)
echo "clang-tidy: $(echo "$files" | wc -w) files"
# One file per process, two at a time; any finding fails (WarningsAsErrors).
if ! echo "$files" | xargs -n 1 -P "$(nproc)" clang-tidy -p "$build" --quiet 2> >(grep -v "warnings generated" >&2); then
  echo "lint: clang-tidy found problems" >&2
  exit 1
fi
echo "lint: clean"
