#!/usr/bin/env bash
# Map one rtl/ module to the iCE40UP5K with Yosys (synth_ice40, DSP inference
# on) and print its resource use. Fails if Yosys reports an error or warns
# about latches or multiple drivers, or if the module does not fit the device.
# usage: synth_check.sh <module> <workdir>
set -euo pipefail
top="$1"
work="${2:-build/synth_check}"
rtl="$(cd "$(dirname "$0")/../rtl" && pwd)"
mkdir -p "$work"
log="$work/$top.yosys.log"
yosys -q -l "$log" -p "read_verilog -I$rtl $rtl/*.v; synth_ice40 -dsp -top $top; tee -o $work/$top.stat.txt stat" >/dev/null
# A latch, a net with two drivers, or any Yosys warning fails the check.
if grep -E "^Latch inferred|conflicting drivers|^Warning:|^ERROR" "$log" >&2; then
  echo "synth_check: $top: Yosys reported the problems above" >&2
  exit 1
fi
cells() { awk -v c="$1" '$1 == c {n = $2} END {print n + 0}' "$work/$top.stat.txt"; }
ff=0
for c in SB_DFF SB_DFFE SB_DFFSR SB_DFFSS SB_DFFESR SB_DFFESS SB_DFFR SB_DFFS SB_DFFER SB_DFFES; do
  ff=$((ff + $(cells "$c")))
done
echo "$top mapped to iCE40: $(cells SB_LUT4) LUT4, $ff flip-flops, $(cells SB_CARRY) carries," \
  "$(cells SB_MAC16) SB_MAC16, $(cells SB_RAM40_4K) SB_RAM40_4K"
