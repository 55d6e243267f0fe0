#!/usr/bin/env bash
# make fuzz: builds the libFuzzer targets with clang++ in their own build
# directory and runs each for a set time on a copy of its seed corpus
# (fuzz/corpus/<target>/), then prints executions and crashes per target.
# usage: fuzz/run.sh <build-dir> <seconds per target> [target...]
# With FUZZ_RUNS=N in the environment each target runs until N executions
# instead (seconds 0: no time limit), the way the figures in
# docs/reliability.md were made.
# A crash leaves its input in <build-dir>/crashes/<target>/; rerun it with
#   <build-dir>/<target> <that file>
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-build-fuzz}"
seconds="${2:-60}"
shift 2 || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_frame_decoder fuzz_machine_toml fuzz_gcode fuzz_board_rx)
# fuzz_board_rx runs on the board twin; its corpus is then replayed on the
# Verilated board (fuzz_board_rx_rtl, about an input a second) for the same
# time, or at most REPLAY_SECONDS.
replay_max="${REPLAY_SECONDS:-600}"
build_targets=("${targets[@]}")
for t in "${targets[@]}"; do [ "$t" = fuzz_board_rx ] && build_targets+=(fuzz_board_rx_rtl); done
cd "$root"
gen=""
command -v ninja >/dev/null 2>&1 && gen="-G Ninja"
test -f "$build/CMakeCache.txt" ||
  cmake -S . -B "$build" $gen -DCMAKE_CXX_COMPILER=clang++ -DMC_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" --target "${build_targets[@]}" -j "$(nproc)"

declare -A dict=([fuzz_machine_toml]=fuzz/dict/machine_toml.dict [fuzz_gcode]=fuzz/dict/gcode.dict
  [fuzz_frame_decoder]=fuzz/dict/frame.dict)
# Seeds kept elsewhere in the tree: the G-code reference programs, the built-in machine.
declare -A seeds=([fuzz_gcode]=tests/gcode/*.ngc [fuzz_machine_toml]=configs/default.toml)
# The longest input tried: past it, longer inputs add time, not new paths.
declare -A max_len=([fuzz_frame_decoder]=512 [fuzz_gcode]=1024 [fuzz_machine_toml]=4096 [fuzz_board_rx]=512)
failed=0
summary=()

# The twin fuzzer's corpus on the Verilated board, newest inputs first, in
# batches of 16 until the time is spent: the same rule, on the RTL.
replay_board_rx() {
  local work="$1" budget="$2" rtl="$build/fuzz_board_rx_rtl" log="$build/fuzz_board_rx_rtl.log"
  local t0=$SECONDS done=0 rc=0 files=()
  [ "$budget" -le "$replay_max" ] || budget=$replay_max
  [ "$budget" -ge 10 ] || budget=10
  rm -f "$log"
  mapfile -t files < <(ls -t "$work")
  local total=${#files[@]} i=0
  while [ $i -lt "$total" ] && [ $((SECONDS - t0)) -lt "$budget" ]; do
    local batch=("${files[@]:$i:16}")
    set +e
    "$rtl" "${batch[@]/#/$work/}" >>"$log" 2>&1
    rc=$?
    set -e
    i=$((i + ${#batch[@]}))
    done=$i
    [ "$rc" -eq 0 ] || break
  done
  local line
  line=$(printf '%-20s %6s s  %12s of %d inputs replayed on the RTL  %d failed' fuzz_board_rx_rtl \
    "$((SECONDS - t0))" "$done" "$total" "$((rc != 0))")
  echo "$line"
  summary+=("$line")
  if [ "$rc" -ne 0 ]; then
    failed=1
    echo "  see $log (the input is on its last 'Running:' line)" >&2
    tail -n 30 "$log" >&2
  fi
}
for t in "${targets[@]}"; do
  name="${t#fuzz_}"
  work="$build/corpus/$name"
  crashes="$build/crashes/$t"
  mkdir -p "$work" "$crashes"
  rm -f "$crashes"/*
  cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
  # shellcheck disable=SC2086  # the glob is meant to expand
  [ -n "${seeds[$t]:-}" ] && cp -n ${seeds[$t]} "$work"/
  args=(-max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$crashes/" -timeout=10
    -rss_limit_mb=2048 -max_len="${max_len[$t]}")
  [ -n "${dict[$t]:-}" ] && args+=(-dict="${dict[$t]}")
  [ -n "${FUZZ_RUNS:-}" ] && args+=(-runs="$FUZZ_RUNS")
  log="$build/$t.log"
  set +e
  start=$SECONDS
  "$build/$t" "${args[@]}" "$work" >"$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  n_crash=$(find "$crashes" -type f | wc -l)
  line=$(printf '%-20s %6s s  %12s executions  %4s execs/s  %d crashes' "$t" "$((SECONDS - start))" "${execs:-?}" \
    "$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)" "$n_crash")
  echo "$line"
  summary+=("$line")
  if [ "$rc" -ne 0 ] || [ "$n_crash" -ne 0 ]; then
    failed=1
    echo "  see $log; inputs in $crashes/" >&2
    tail -n 30 "$log" >&2
  fi
  if [ "$t" = fuzz_board_rx ]; then
    replay_board_rx "$work" "$((SECONDS - start))"
  fi
done
echo "fuzz: ${#targets[@]} targets, ${FUZZ_RUNS:+$FUZZ_RUNS executions or }$seconds s each (0: no limit)"
printf '  %s\n' "${summary[@]}"
exit $failed
