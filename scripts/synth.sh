#!/usr/bin/env bash
# `make synth`: the board bitstream and its utilization and timing.
# Yosys synth_ice40 -dsp -abc9 -dff -> nextpnr-ice40 --up5k --package sg48 with
# constraints/icebreaker.pcf at the real clock (--freq 12) -> icepack.
# Writes <out>/motioncore_icebreaker.bin and <out>/report.json with
#   lut, lut_total  logic cells used / available (nextpnr ICESTORM_LC; each
#                   holds one LUT4 and its flip-flop)
#   lut4            LUT4s after Yosys mapping (Yosys stat)
#   dsp, ebr        SB_MAC16 and block RAMs used (nextpnr)
#   fmax_mhz        achieved Fmax of the clock (nextpnr), clock_mhz its target
#   naxes           axes built
#   steppers        axes built with a step generator (bit a: axis a)
#   servo           whether the PID loops are built
# and prints a summary. Exits 1 if nextpnr cannot place the design, or if the
# Fmax is below the clock.
# usage: [NAXES=n] synth.sh [out-dir] [--modules]
#   NAXES      axes to build (default: the top's parameter, 3)
#   HANDWHEEL  0 leaves the handwheel decoder out (default 1)
#   STEPPERS   axes with a step generator, bit a for axis a (default 0)
#   SERVO      0 builds the board without the PID loops (default 1): with
#              STEPPERS=7, the stepper board (make synth-stepper)
#   --modules  also print a per-module LUT4 breakdown (a separate, unflattened
#              Yosys run; it does not affect the bitstream)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
# ABC9 with flip-flops in its scope maps the three-axis board in about 150
# fewer logic cells than the default ABC pass; at 99 % of the device the
# default netlist did not route, at 95 % this one does (docs/board.md).
yosys_flags="-dsp -abc9 -dff"
out="${1:-$root/build/synth}"
mode="${2:-}"
top=motioncore_icebreaker
clock_mhz=12
seed=1
mkdir -p "$out"
rtl="$root/rtl"

echo "synth: yosys (log: $out/yosys.log)"
chp=""
if [ -n "${NAXES:-}" ]; then chp="chparam -set NAXES $NAXES $top;"; fi
if [ -n "${HANDWHEEL:-}" ]; then chp="$chp chparam -set HANDWHEEL $HANDWHEEL $top;"; fi
if [ -n "${STEPPERS:-}" ]; then chp="$chp chparam -set STEPPERS $STEPPERS $top;"; fi
if [ -n "${SERVO:-}" ]; then chp="$chp chparam -set SERVO $SERVO $top;"; fi
yosys -q -l "$out/yosys.log" -p "read_verilog -I$rtl $rtl/*.v; $chp synth_ice40 $yosys_flags -top $top -json $out/$top.json; tee -q -o $out/stat.txt stat" >/dev/null
if grep -E "^Latch inferred|conflicting drivers|^ERROR" "$out/yosys.log" >&2; then
  echo "synth: Yosys reported the problems above" >&2
  exit 1
fi
lut4=$(awk '$1 == "SB_LUT4" {n = $2} END {print n + 0}' "$out/stat.txt")

echo "synth: nextpnr-ice40 --up5k --package sg48 --freq $clock_mhz (log: $out/nextpnr.log)"
status=0
nextpnr-ice40 --up5k --package sg48 --pcf "$root/constraints/icebreaker.pcf" --json "$out/$top.json" \
  --freq "$clock_mhz" --seed "$seed" --report "$out/nextpnr_report.json" --asc "$out/$top.asc" \
  >"$out/nextpnr.log" 2>&1 || status=$?
param() { grep -oE "parameter integer $1 += [0-9]+" "$rtl/$top.v" | grep -oE "[0-9]+$"; }
naxes=${NAXES:-$(param NAXES)}
steppers=${STEPPERS:-$(param STEPPERS)}
servo=${SERVO:-$(param SERVO)}
servo_json=$([ "$servo" != 0 ] && echo true || echo false)
if [ $status -ne 0 ]; then
  grep -E "ERROR|Utilisation|ICESTORM_LC" "$out/nextpnr.log" | tail -8 >&2
  # What nextpnr counted before it gave up, for the record (no Fmax: not placed).
  lc_line=$(grep -E "ICESTORM_LC:" "$out/nextpnr.log" | tail -1 | sed -E 's/.*ICESTORM_LC: *([0-9]+)\/ *([0-9]+).*/\1 \2/')
  read -r lc lc_total <<<"${lc_line:-0 0}"
  jq -n --argjson lut "$lc" --argjson lut_total "$lc_total" --argjson lut4 "$lut4" --argjson naxes "$naxes" \
    --argjson clock "$clock_mhz" --argjson steppers "$steppers" --argjson servo "$servo_json" \
    '{lut: $lut, lut_total: $lut_total, lut4: $lut4, dsp: null, ebr: null, fmax_mhz: null, clock_mhz: $clock,
      naxes: $naxes, steppers: $steppers, servo: $servo, fits: false}' >"$out/report.json"
  echo "synth: nextpnr failed (exit $status): the design does not fit or cannot be routed; see $out/nextpnr.log" >&2
  exit 1
fi
icepack "$out/$top.asc" "$out/$top.bin"

# Numbers from nextpnr's own JSON report.
rep="$out/nextpnr_report.json"
used() { jq -r ".utilization.\"$1\".used" "$rep"; }
avail() { jq -r ".utilization.\"$1\".available" "$rep"; }
lc=$(used ICESTORM_LC)
lc_total=$(avail ICESTORM_LC)
dsp=$(used ICESTORM_DSP)
ebr=$(used ICESTORM_RAM)
fmax=$(jq -r '[.fmax[] | .achieved] | min' "$rep")
jq -n --argjson lut "$lc" --argjson lut_total "$lc_total" --argjson lut4 "$lut4" --argjson dsp "$dsp" \
  --argjson ebr "$ebr" --argjson fmax "$fmax" --argjson clock "$clock_mhz" --argjson naxes "$naxes" \
  --argjson steppers "$steppers" --argjson servo "$servo_json" \
  '{lut: $lut, lut_total: $lut_total, lut4: $lut4, dsp: $dsp, ebr: $ebr,
    fmax_mhz: ($fmax * 100 | round / 100), clock_mhz: $clock, naxes: $naxes, steppers: $steppers,
    servo: $servo, fits: true}' >"$out/report.json"

pct() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.0f", 100 * a / b}'; }
echo
kind=$([ "$servo" != 0 ] && echo "servo loops" || echo "no servo loops")
echo "motioncore_icebreaker, $naxes axes, $kind, step generators on axes mask $steppers, iCE40UP5K-SG48 (nextpnr, seed $seed)"
printf "  logic cells  %5s / %s  (%s %%; LUT4 after Yosys: %s)\n" "$lc" "$lc_total" "$(pct "$lc" "$lc_total")" "$lut4"
printf "  SB_MAC16     %5s / %s\n" "$dsp" "$(avail ICESTORM_DSP)"
printf "  block RAM    %5s / %s\n" "$ebr" "$(avail ICESTORM_RAM)"
printf "  Fmax         %5s MHz at a %s MHz clock (%.1fx)\n" "$(jq -r .fmax_mhz "$out/report.json")" "$clock_mhz" \
  "$(awk -v f="$fmax" -v c="$clock_mhz" 'BEGIN {print f / c}')"
echo "  bitstream    $out/$top.bin"
echo "  report       $out/report.json"

if [ "$mode" = "--modules" ]; then
  echo
  echo "LUT4 per module (Yosys synth_ice40 $yosys_flags -noflatten; cross-module optimization off, so the sum is a little higher):"
  yosys -q -l "$out/yosys_modules.log" -p "read_verilog -I$rtl $rtl/*.v; $chp synth_ice40 $yosys_flags -noflatten -top $top; tee -q -o $out/stat_modules.txt stat" >/dev/null
  awk '/^=== / {m = $2} $1 == "SB_LUT4" && m != "" {printf "  %-40s %6d\n", m, $2}' "$out/stat_modules.txt"
fi

if awk -v f="$fmax" -v c="$clock_mhz" 'BEGIN {exit !(f < c)}'; then
  echo "synth: Fmax $fmax MHz misses the $clock_mhz MHz clock" >&2
  exit 1
fi
