#!/usr/bin/env bash
# Map one rtl/ module to the iCE40UP5K with Yosys (synth_ice40, DSP inference
# on) and print its resource use. Fails if Yosys reports an error or warns
# about latches or multiple drivers, or if the module does not fit the device.
# usage: synth_check.sh <module> <workdir> [--pnr]
#   --pnr  also place the module alone on the UP5K with nextpnr and print the
#          packed logic-cell count (informational: a module with more ports
#          than the package has pins, or more cells than the device, is
#          reported, not failed).
set -euo pipefail
top="$1"
work="${2:-build/synth_check}"
pnr="${3:-}"
rtl="$(cd "$(dirname "$0")/../rtl" && pwd)"
mkdir -p "$work"
log="$work/$top.yosys.log"
yosys -q -l "$log" -p "read_verilog -I$rtl $rtl/*.v; synth_ice40 -dsp -top $top -json $work/$top.json; tee -o $work/$top.stat.txt stat" >/dev/null
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
if [ "$pnr" = "--pnr" ]; then
  nextpnr-ice40 --up5k --package sg48 --json "$work/$top.json" --pcf-allow-unconstrained \
    >"$work/$top.nextpnr.log" 2>&1 || true
  lc=$(grep -E "ICESTORM_LC:" "$work/$top.nextpnr.log" | tail -1 | sed 's/^Info:[[:space:]]*//')
  echo "$top placed alone on the UP5K (nextpnr): ${lc:-no utilization report, see $work/$top.nextpnr.log}"
fi
