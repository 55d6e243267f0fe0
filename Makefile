# MotionCore front door. CMake does the building; this file only names the
# everyday commands. See README.md.
BUILD      ?= build
BUILD_SAN  ?= build-san
BUILD_FUZZ ?= build-fuzz
# Seconds per fuzz target (make fuzz); docs/reliability.md has the figures.
FUZZ_SECONDS ?= 60
# Executions per fuzz target instead of seconds (make fuzz FUZZ_RUNS=10000000).
FUZZ_RUNS  ?=
# Board seconds and job of the link soak (make soak).
SOAK_SECONDS ?= 3600
SOAK_JOB   ?= examples/profile.nc
JOBS       ?= $(shell nproc)
CMAKE_GEN  := $(shell command -v ninja >/dev/null 2>&1 && echo "-G Ninja")

.PHONY: all deps configure test test-sanitize bench level-bench lint fuzz format clean regs synth synth-stepper prog flash formal readme-bench soak

all: deps configure
	cmake --build $(BUILD) -j $(JOBS)

deps:
	@scripts/deps.sh

configure:
	@test -f $(BUILD)/CMakeCache.txt || cmake -S . -B $(BUILD) $(CMAKE_GEN)

test: all
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

# The sample-period benchmark: the 10 ms PC loop against the FPGA loop at
# 10 ms .. its shortest Ts, on the built-in machine (configs/default.toml).
# Writes $(BUILD)/bench/report.md, results.csv and plots/.
bench: all
	$(BUILD)/motionctl bench --out $(BUILD)/bench

# The levelling benchmark of docs/levelling.md on the virtual board: a
# 0.1 mm engraving of the tilted, dished workpiece without levelling, with
# the source paper's end-point method and with a 9 x 7 map the board's probe
# takes first; prints the depth error of each, measured on the plant.
level-bench: all
	$(BUILD)/motionctl --sim level compare --probe

# The same C++ tests under AddressSanitizer + UndefinedBehaviorSanitizer.
# Synthesis and formal tests are skipped: they test the tools' view of the RTL,
# not our C++; so are the sender clients (label client: cncjs, bCNC), whose
# server code the in-process Grbl tests cover under the sanitizers, and the
# second run of the CLI tests on the Verilated board (Rtl.*): the same CLI
# code runs in their first run, on the twin. SAN_SKIP: the labels skipped
# (CI adds rtl, the C/RTL comparisons, for time: .ci/run says why).
SAN_SKIP   ?= synth|formal|paced|client
test-sanitize: deps
	@test -f $(BUILD_SAN)/CMakeCache.txt || cmake -S . -B $(BUILD_SAN) $(CMAKE_GEN) -DMC_SANITIZE=ON
	cmake --build $(BUILD_SAN) -j $(JOBS)
	ctest --test-dir $(BUILD_SAN) --output-on-failure -j $(JOBS) -LE '$(SAN_SKIP)' -E '^Rtl\.'

lint: deps
	scripts/lint.sh $(BUILD)

# Every formal proof of the RTL, by induction (docs/formal.md); `make test`
# runs only the quick ones. Logs and traces: $(BUILD)/formal/<block>/.
formal: deps
	FORMAL_DIR=$(BUILD)/formal scripts/formal.sh -j $(JOBS)

# libFuzzer targets (fuzz/), built with clang++ in $(BUILD_FUZZ): each runs
# FUZZ_SECONDS on its seed corpus (or, with FUZZ_RUNS=N, N executions);
# prints executions and crashes per target.
fuzz: deps
	FUZZ_RUNS=$(FUZZ_RUNS) fuzz/run.sh $(BUILD_FUZZ) $(FUZZ_SECONDS)

# The link soak of issue 18: SOAK_SECONDS of board time of SOAK_JOB, looped,
# over a line that flips and drops 1e-3 of the bytes each way; fails unless
# 0 segments were lost, doubled or reordered. Not in `make test`, which runs
# 30 s of it (test_link_soak). docs/reliability.md has the figures.
soak: deps configure
	cmake --build $(BUILD) --target motionctl -j $(JOBS)
	$(BUILD)/motionctl sim soak --board-seconds $(SOAK_SECONDS) --job $(SOAK_JOB)

format:
	clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	rm -rf $(BUILD) $(BUILD_SAN) $(BUILD_FUZZ)

# Copy the benchmark table of the last full `make bench` into README.md.
readme-bench:
	scripts/bench_readme.sh $(BUILD)/bench/report.md README.md

# Regenerate rtl/board_regs.vh and the register table of docs/protocol.md
# from hls/board_regs.hpp (test_board_regs fails when they are stale).
regs: deps configure
	cmake --build $(BUILD) --target gen_board_regs
	$(BUILD)/gen_board_regs --vh > rtl/board_regs.vh
	scripts/splice_md.sh docs/protocol.md "<!-- GENERATED register table: make regs -->" \
	  "<!-- end of generated table -->" $(BUILD)/gen_board_regs --md

# Bitstream and utilization/timing summary: build/synth/ (scripts/synth.sh).
# The servo board: three PID loops on H-bridges. synth-stepper: the stepper
# board, a step generator on every axis and no loops (build/synth-stepper/).
# The UP5K holds one or the other, not both (docs/board.md).
synth: deps
	scripts/synth.sh $(BUILD)/synth

synth-stepper: deps
	STEPPERS=7 SERVO=0 scripts/synth.sh $(BUILD)/synth-stepper

# Program the iCEBreaker (board on USB; docs/bringup.md). prog loads the
# bitstream into the FPGA's configuration SRAM (iceprog -S): it runs at once
# and is gone at the next power cycle, the safe way to try a build. flash
# writes it to the board's SPI flash (iceprog without -S), which the FPGA
# loads at every power-up. SYNTH_DIR=build/synth-stepper programs the
# stepper board.
SYNTH_DIR ?= $(BUILD)/synth
prog: $(SYNTH_DIR)/motioncore_icebreaker.bin
	iceprog -S $<

flash: $(SYNTH_DIR)/motioncore_icebreaker.bin
	iceprog $<

$(SYNTH_DIR)/motioncore_icebreaker.bin:
	@echo "no bitstream in $(SYNTH_DIR): run make synth (or make synth-stepper) first" >&2; exit 2
