#!/usr/bin/env bash
# Formal proofs of the RTL's `ifdef FORMAL` properties (docs/formal.md).
# usage: scripts/formal.sh [-jN | -j N] [--mutants] [block...]
#                                  (no block: all of them)
#        scripts/formal.sh --list [quick]
#                                  the block names; quick: those `make test`
#                                  runs (tests/formal.cmake), the rest only
#                                  `make formal` (they take minutes)
#
# Each block: Yosys reads its files with -formal (FORMAL and FORMAL_TOP_<top>
# defined) and writes an SMT-LIB2 model; yosys-smtbmc then runs
#   1. BMC from reset for DEPTH steps (the base case),
#   2. k-induction with the same DEPTH (the unbounded proof), unless the
#      block is marked bmc, in which case step 1 is the whole result,
#   3. cover: every cover statement must be reached within CDEPTH steps.
# One line per block: PASS/FAIL, mode, depths, seconds. Exit status 1 if any
# block fails, 2 on a usage error. Logs, models and traces (VCD of any failed
# step) are kept in $FORMAL_DIR/<block>/ (default build/formal); with
# FORMAL_TRACES=1 also a VCD of each cover's trace.
# --mutants: each block instead proves a copy of its files with one plausible
# bug injected (MUT below, a sed expression): the line says CAUGHT and which
# step failed, or MISSED (exit status 1) if the broken copy still passes.
# The solver is the block's (FORMAL_SOLVER overrides): z3, or cvc5 where z3
# 4.8 spends long on the model's definitions.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
rtl="$root/rtl"
outdir="${FORMAL_DIR:-$root/build/formal}"

# block: top | files (repo-relative) | read_verilog options | hierarchy options
#        | Yosys commands after prep | model | solver | mode | DEPTH | CDEPTH
# model bv: every state one bit-vector (write_smt2 -stbv), logic QF_BV, which
#   z3 bit-blasts: fast on XOR networks such as the CRC, but a memory becomes
#   a bit-vector too, which z3 4.8 cannot digest;
# model arrays: memories as SMT arrays (write_smt2's default encoding).
# mode prove: BMC and k-induction; bmc: BMC only.
declare -A CFG
CFG[crc16_ccitt]="crc16_ccitt|rtl/crc16_ccitt.v||||bv|z3|prove|10|90"
CFG[uart_tx]="uart_tx|rtl/uart_tx.v||||bv|z3|prove|4|130"
CFG[uart_rx]="uart_rx|rtl/uart_rx.v||||bv|z3|prove|4|240"
CFG[mc_safety]="mc_safety|rtl/mc_safety.v||||bv|z3|prove|4|20"
CFG[seg_fifo]="seg_fifo|rtl/seg_fifo.v||||arrays|z3|prove|4|20"
CFG[link_rx]="link_rx|rtl/link_rx.v rtl/crc16_ccitt.v|-D FORMAL_NO_PAY_RAM||delete t:\$mem_v2; setundef -undriven -anyseq;|bv|z3|prove|12|80"
CFG[link_rx_pay]="link_rx|rtl/link_rx.v rtl/crc16_ccitt.v||||arrays|z3|prove|12|0"
CFG[quad_decoder]="quad_decoder|rtl/quad_decoder.v||-chparam FILT_W 4||bv|cvc5|prove|4|30"
CFG[quad_rate]="quad_decoder|rtl/quad_decoder.v|-D FORMAL_QUAD_RATE|-chparam FILT_W 4||bv|cvc5|prove|6|40"
CFG[step_gen]="step_gen|rtl/step_gen.v||-chparam PW_W 4 -chparam BL_W 3||bv|z3|prove|6|40"
CFG[seg_fifo_aw4]="seg_fifo|rtl/seg_fifo.v||-chparam AW 4||arrays|z3|prove|4|40"
ORDER=(crc16_ccitt uart_tx uart_rx mc_safety step_gen seg_fifo seg_fifo_aw4 link_rx link_rx_pay quad_decoder quad_rate)
QUICK=(crc16_ccitt uart_tx uart_rx mc_safety seg_fifo link_rx quad_decoder)

# One plausible bug per block, as a sed expression on its files.
declare -A MUT
MUT[crc16_ccitt]="s/(crc_o\[15\] ^ sh\[7\]) ? 16'h1021/(crc_o[15] ^ sh[7]) ? 16'h1031/"   # wrong polynomial
MUT[uart_tx]="s/left <= 4'd9;/left <= 4'd8;/"                                               # a data bit short
MUT[uart_rx]="s/valid_o <= rx_i;/valid_o <= 1'b1;/"                                         # no stop-bit check
MUT[mc_safety]="s/arm_set_i \&\& fault_o == 16'd0) armed_o/arm_set_i) armed_o/"             # arms over a fault
MUT[step_gen]="s/wire            ready = owed \&\& fwd == dir_o;/wire            ready = owed;/"  # steps the old way
MUT[seg_fifo]="s/if (do_rd) rp <= rp + 1'b1;/if (do_rd \&\& !do_wr) rp <= rp + 1'b1;/"      # read lost beside a write
MUT[seg_fifo_aw4]="${MUT[seg_fifo]}"
MUT[link_rx]="s/{byte_i, crc_lo} == crc/{crc_lo, byte_i} == crc/"                         # CRC bytes swapped
MUT[link_rx_pay]="${MUT[link_rx]}"
MUT[quad_decoder]="s/: ~(sync\[1\] ^ filt\[0\]);/: (sync[1] ^ filt[0]);/"                  # B edges counted backwards
MUT[quad_rate]="s/straddle = |(drop\[1:0\]/straddle = |(differ[1:0]/"                        # error on a pending edge

if [ "${1:-}" = --list ]; then
  if [ "${2:-}" = quick ]; then echo "${QUICK[*]}"; else echo "${ORDER[*]}"; fi
  exit 0
fi
jobs=1
case "${1:-}" in
  -j) jobs="${2:?-j needs a number}"; shift 2 ;;
  -j*) jobs="${1#-j}"; shift ;;
esac
mutants=0
if [ "${1:-}" = --mutants ]; then
  mutants=1
  shift
fi
blocks=("$@")
[ ${#blocks[@]} -eq 0 ] && blocks=("${ORDER[@]}")
for b in "${blocks[@]}"; do
  if [ -z "${CFG[$b]:-}" ]; then
    echo "formal.sh: no block '$b' (blocks: ${ORDER[*]})" >&2
    exit 2
  fi
done
for tool in yosys yosys-smtbmc z3 cvc5; do  # cvc5: quad_decoder
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "formal.sh: $tool not found (scripts/deps.sh installs it)" >&2
    exit 2
  fi
done

# Run one block; print its line; return 0 on PASS.
run_block() {
  local b="$1" top files ropt hopt post model solver mode depth cdepth
  IFS='|' read -r top files ropt hopt post model solver mode depth cdepth <<<"${CFG[$b]}"
  solver="${FORMAL_SOLVER:-$solver}"
  local work="$outdir/$b"
  local tdepth="$cdepth"  # long enough for a whole byte or frame
  [ $mutants -eq 1 ] && work="$outdir/$b.mutant" && cdepth=0  # asserts only
  rm -rf "$work"
  mkdir -p "$work"
  local t0 paths="" f
  t0=$(date +%s.%N)
  for f in $files; do paths="$paths $root/$f"; done
  if [ $mutants -eq 1 ]; then
    paths=""
    for f in $files; do
      mkdir -p "$work/src/$(dirname "$f")"
      sed "${MUT[$b]}" "$root/$f" >"$work/src/$f"
      paths="$paths $work/src/$f"
    done
    if (cd "$work/src" && for f in $files; do cmp -s "$f" "$root/$f" || exit 1; done); then
      printf "ERROR %-14s the mutant changes nothing: %s\n" "$b" "${MUT[$b]}"
      return 1
    fi
  fi
  local smt=(yosys-smtbmc -s "$solver" --noprogress) stbv=""
  if [ "$model" = bv ]; then
    smt+=(--logic QF_BV)
    stbv="-stbv"
  fi
  # Cover traces take longer to write than to find: only on request. With
  # z3 the asserts along them are not checked again (--noinfo): steps 1 and
  # 2 prove them. (cvc5 gives no model for the covers with --noinfo.)
  local what="" ok=1 ctrace=() cinfo=(--noinfo)
  [ -n "${FORMAL_TRACES:-}" ] && ctrace=(--dump-vcd "$work/cover%.vcd")
  [ "$solver" = z3 ] || cinfo=()
  if ! yosys -q -l "$work/yosys.log" -p "read_verilog -formal -D FORMAL -D FORMAL_TOP_$top $ropt -I$rtl $paths; hierarchy -top $top $hopt; prep -top $top; $post flatten; opt; async2sync; dffunmap; write_smt2 $stbv -wires $work/model.smt2" >/dev/null 2>&1; then
    ok=0; what="yosys failed (see $work/yosys.log)"
  elif ! "${smt[@]}" --presat -t "$depth" --dump-vcd "$work/bmc.vcd" "$work/model.smt2" >"$work/bmc.log" 2>&1; then
    ok=0; what="BMC failed within $depth steps ($work/bmc.log, bmc.vcd)"
  elif [ "$mode" = prove ] && ! "${smt[@]}" -i -t "$depth" --dump-vcd "$work/induction.vcd" "$work/model.smt2" >"$work/induction.log" 2>&1; then
    ok=0; what="induction failed at depth $depth ($work/induction.log, induction.vcd)"
  elif [ "$cdepth" -gt 0 ] && ! "${smt[@]}" "${cinfo[@]}" -c -t "$cdepth" "${ctrace[@]}" "$work/model.smt2" >"$work/cover.log" 2>&1; then
    ok=0; what="cover failed within $cdepth steps ($work/cover.log)"
  fi
  local secs ncov reached
  secs=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  if [ $mutants -eq 1 ]; then
    if [ $ok -eq 1 ]; then
      printf "MISSED %-14s %-60s %6s s\n" "$b" "still proven: ${MUT[$b]}" "$secs"
      return 1
    elif [[ "$what" == yosys* ]]; then
      printf "ERROR %-14s %-61s %6s s\n" "$b" "$what" "$secs"
      return 1
    fi
    # An induction failure may start from an unreachable state: look for a
    # trace from reset as long as the covers' before calling it caught.
    if [[ "$what" == induction* ]] && [ "$tdepth" -gt "$depth" ]; then
      if "${smt[@]}" --presat -t "$tdepth" "$work/model.smt2" >"$work/bmc_long.log" 2>&1; then
        printf "WEAK   %-14s %-60s %6s s\n" "$b" "induction fails, but no trace from reset within $tdepth" "$secs"
        return 0
      fi
      what="BMC failed within $tdepth steps"
      rm -f "$work/induction.log"
      secs=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    fi
    local at
    at=$(grep -shoE "Assert failed in [^:]*: [^ ]*" "$work"/*.log | head -1 | sed -E 's|.*/src/||; s|:[0-9.]+-([0-9]+)[.].*|:\1|')
    printf "CAUGHT %-14s %-60s %6s s\n" "$b" "${what%% (*}${at:+: assert at $at}" "$secs"
    return 0
  fi
  if [ $ok -eq 1 ]; then
    ncov=$(grep -c "yosys-smt2-cover" "$work/model.smt2" || true)
    reached=$(grep -sc "Reached cover statement" "$work/cover.log" || true)
    if [ "$mode" = prove ]; then
      what="induction k=$depth (BMC $depth)"
    else
      what="BMC depth $depth only"
    fi
    if [ "$cdepth" -gt 0 ]; then
      what="$what, covers $reached/$ncov within $cdepth steps"
    else
      what="$what, no covers"
    fi
    printf "PASS %-14s %-62s %6s s\n" "$b" "$what" "$secs"
    return 0
  fi
  printf "FAIL %-14s %-62s %6s s\n" "$b" "$what" "$secs"
  grep -hE "Assert failed|Unreached cover|failed assumption|Solver Error|ERROR" \
    "$work"/*.log 2>/dev/null | head -5 | sed 's/^/     /'
  return 1
}

status=0
if [ "$jobs" -le 1 ] || [ ${#blocks[@]} -le 1 ]; then
  for b in "${blocks[@]}"; do run_block "$b" || status=1; done
else
  # Up to $jobs blocks at once; lines printed in the order asked for.
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  running=0
  for b in "${blocks[@]}"; do
    if [ $running -ge "$jobs" ]; then
      wait -n || true
      running=$((running - 1))
    fi
    (run_block "$b" >"$tmp/$b.out"; echo $? >"$tmp/$b.rc") &
    running=$((running + 1))
  done
  wait || true
  for b in "${blocks[@]}"; do
    cat "$tmp/$b.out"
    [ "$(cat "$tmp/$b.rc")" = 0 ] || status=1
  done
fi
exit $status
