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
lut=$(awk '/SB_LUT4/ {print $2}' "$work/$top.stat.txt" | tail -1)
dsp=$(awk '/SB_MAC16/ {print $2}' "$work/$top.stat.txt" | tail -1)
ebr=$(awk '/SB_RAM40_4K/ {print $2}' "$work/$top.stat.txt" | tail -1)
echo "$top on iCE40UP5K: ${lut:-0} LUT4 of 5280, ${dsp:-0} SB_MAC16 of 8, ${ebr:-0} SB_RAM40_4K of 30"
[ "${lut:-0}" -le 5280 ] && [ "${dsp:-0}" -le 8 ] && [ "${ebr:-0}" -le 30 ]
