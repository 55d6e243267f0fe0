// The handwheel jog on the virtual board: a 100-PPR wheel on HW_A/HW_B
// (VirtualBoard::turn_handwheel) and the board's MPG jog set through
// host/machine/mpg.hpp. Each detent moves the selected axis's command by
// the step, and the plant with it (open-loop steppers, configs/
// stepper_router.toml: the driver's STEP count is exact, and no step is
// lost); the twin's fast-forward loses and moves no edge (the
// Verilated board, clock by clock, ends in the same state); turning MPG off
// drops what is pending. Board time only: the link's clock is the board's.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/mpg.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;
using machine::MpgSetting;

constexpr int kX = 0, kZ = 2;

machine::MachineConfig stepper_router() {
  return machine::load_machine(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml");
}

struct Rig {
  explicit Rig(sim::BoardEngine e = sim::BoardEngine::Twin)
      : cfg(stepper_router()), board(cfg, 0, e), stream(board), link(stream) {
    link.connect();
    link.write(br::WDOG, (1u << 24) - 1);  // the longest: the tests read at their own pace
    machine::setup_axes(link, cfg);
  }
  void arm() { machine::enable_machine_axes(link, cfg, {0, 1, 2}, {}); }
  // Turns the wheel and follows the board until every turn asked is done
  // and the axis stands where its command ends.
  machine::MpgSample turn(int axis, int detents, double seconds = 0.02) {
    board.turn_handwheel(detents, seconds);
    return machine::follow_mpg(link, axis, board.handwheel_done_s() - board.board_seconds(), {});
  }
  // The plant of `axis`: the STEP pulses its driver took (where the table
  // is sent, exactly), and the table itself in counts.
  int64_t steps(int axis) { return board.driver_steps(axis); }
  int64_t table_counts(int axis) {
    return std::llround(board.position_m(axis) * machine::counts_per_m(cfg.axes[size_t(axis)]));
  }
  int32_t reg(int axis, uint16_t off) { return int32_t(link.read(br::axis(axis, off))); }

  machine::MachineConfig cfg;
  sim::VirtualBoard board;
  sim::BoardStream stream;
  host::BoardLink link;
};

TEST(VBoardMpg, ParsesTheOperatorsWords) {
  EXPECT_EQ(machine::parse_mpg("x10"), (MpgSetting{kX, 10}));
  EXPECT_EQ(machine::parse_mpg("X,100"), (MpgSetting{kX, 100}));
  EXPECT_EQ(machine::parse_mpg("z 1"), (MpgSetting{kZ, 1}));
  EXPECT_EQ(machine::parse_mpg("OFF"), MpgSetting{});
  EXPECT_EQ(machine::mpg_text({1, 100}), "y100");
  EXPECT_EQ(machine::mpg_text({}), "off");
  for (const char* bad : {"", "x", "x5", "a10", "x,,10", "x1000", "10"})
    EXPECT_THROW(machine::parse_mpg(bad), host::InputError) << bad;
  // A detent in mm: counts over the axis's counts per mm (400 on both machines).
  EXPECT_DOUBLE_EQ(machine::mm_per_detent(machine::default_machine(), {kX, 10}), 0.025);
  EXPECT_DOUBLE_EQ(machine::mm_per_detent(stepper_router(), {kZ, 100}), 0.25);
}

TEST(VBoardMpg, EachDetentMovesTheStep) {
  Rig r;
  r.arm();
  machine::set_mpg(r.link, r.cfg, {kX, 10});
  EXPECT_EQ(machine::read_mpg(r.link), (MpgSetting{kX, 10}));
  const int32_t cmd0 = r.reg(kX, br::AX_CMD);
  const int64_t steps0 = r.steps(kX), table0 = r.table_counts(kX);
  struct Turn {
    int step, detents;
  };
  int64_t want = 0;
  for (const Turn t : {Turn{10, 7}, Turn{10, -3}, Turn{1, 5}, Turn{100, 2}, Turn{100, -2}}) {
    machine::set_mpg(r.link, r.cfg, {kX, t.step});
    const machine::MpgSample s = r.turn(kX, t.detents);
    want += int64_t(t.step) * t.detents;
    EXPECT_EQ(s.pending, 0);
    EXPECT_EQ(s.cmd - cmd0, want) << "after " << t.detents << " detents of x" << t.step;
    EXPECT_EQ(s.pos - cmd0, want);
    EXPECT_EQ(r.steps(kX) - steps0, want);
    EXPECT_EQ(r.board.lost_full_steps(kX), 0);
    // The rotor comes to rest near its microstep, not on it: friction
    // holds it within a fraction of a full step (16 counts here).
    r.link.poll(std::chrono::milliseconds(20));
    EXPECT_NEAR(double(r.table_counts(kX) - table0), double(want), 4);
  }
  // The other axes never moved, and the wheel's count is the board's.
  EXPECT_EQ(r.steps(1), 0);
  EXPECT_EQ(r.steps(kZ), 0);
  EXPECT_EQ(r.board.handwheel_count(), (7 - 3 + 5 + 2 - 2) * sim::kHandwheelCountsPerDetent);
  EXPECT_EQ(int32_t(r.link.read(br::HW_POS)), r.board.handwheel_count());
  EXPECT_EQ(r.link.read(br::FAULT), 0u);
}

TEST(VBoardMpg, OffDropsWhatIsPending) {
  Rig r;  // drives off: the board counts the detents but does not move
  machine::set_mpg(r.link, r.cfg, {kZ, 10});
  r.board.turn_handwheel(5, 0.01);
  r.link.poll(std::chrono::milliseconds(20));
  EXPECT_EQ(machine::mpg_pending(r.link), 50);
  r.board.turn_handwheel(-2, 0.01);
  r.link.poll(std::chrono::milliseconds(20));
  EXPECT_EQ(machine::mpg_pending(r.link), 30);
  // Another axis: what was turned for Z must not move X.
  machine::set_mpg(r.link, r.cfg, {kX, 10});
  EXPECT_EQ(machine::mpg_pending(r.link), 0);
  r.board.turn_handwheel(1, 0.01);
  r.link.poll(std::chrono::milliseconds(20));
  EXPECT_EQ(machine::mpg_pending(r.link), 10);
  machine::set_mpg(r.link, r.cfg, {});
  EXPECT_EQ(machine::read_mpg(r.link), MpgSetting{});
  EXPECT_EQ(machine::mpg_pending(r.link), 0);
  r.arm();
  r.link.poll(std::chrono::milliseconds(10));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(r.steps(a), 0) << "axis " << a;
}

TEST(VBoardMpg, RefusesWhatTheMachineOrBoardLacks) {
  Rig r;
  EXPECT_THROW(machine::set_mpg(r.link, r.cfg, {kX, 5}), host::InputError);
  EXPECT_THROW(machine::set_mpg(r.link, r.cfg, {3, 10}), host::InputError);
  EXPECT_THROW(r.board.turn_handwheel(1, -1), host::InputError);
  EXPECT_THROW(r.board.turn_handwheel(sim::kMaxHandwheelDetents + 1, 1), host::InputError);
  EXPECT_EQ(r.link.read(br::MPG), 0u);
}

// What a session leaves behind, for comparing the engines.
struct Record {
  std::vector<int64_t> at;  // after each turn: HW_POS, and per axis CMD, POS, driver steps, table counts
  uint64_t cycles = 0, stepped = 0;
};

// Turns at different speeds, the slow ones with long idle stretches
// between their edges that the twin skips, and a turn asked while the one
// before is still going.
Record session(sim::BoardEngine e) {
  Rig r(e);
  r.arm();
  machine::set_mpg(r.link, r.cfg, {kX, 10});
  Record rec;
  const auto note = [&] {
    rec.at.push_back(int32_t(r.link.read(br::HW_POS)));
    for (int a = 0; a < 3; ++a) {
      rec.at.push_back(r.reg(a, br::AX_CMD));
      rec.at.push_back(r.reg(a, br::AX_POS));
      rec.at.push_back(r.steps(a));
      rec.at.push_back(r.table_counts(a));
    }
  };
  r.turn(kX, 3, 0.05);
  note();
  machine::set_mpg(r.link, r.cfg, {kZ, 1});
  r.turn(kZ, -4, 0);  // as fast as the decoder takes edges
  note();
  machine::set_mpg(r.link, r.cfg, {kX, 100});
  r.board.turn_handwheel(1, 0.03);
  r.turn(kX, -2, 0.01);  // after that one: 0.04 s in all
  note();
  rec.cycles = r.board.cycles();
  rec.stepped = r.board.stepped_clocks();
  return rec;
}

TEST(VBoardMpg, TwinAndRtlAgreeEdgeForEdge) {
  const Record twin = session(sim::BoardEngine::Twin);
  const Record rtl = session(sim::BoardEngine::Rtl);
  EXPECT_EQ(twin.at, rtl.at);
  EXPECT_EQ(twin.cycles, rtl.cycles);
  // The twin skipped the idle stretches between the edges.
  EXPECT_LT(twin.stepped * 2, twin.cycles);
  // What the turns should have done: X +30 - 100 steps, Z -4 (the last
  // record: HW_POS, then CMD, POS, steps, table of each axis).
  constexpr size_t kRec = 1 + 3 * 4, kLast = 2 * kRec;
  ASSERT_EQ(twin.at.size(), 3 * kRec);
  EXPECT_EQ(twin.at[kLast], (3 - 4 + 1 - 2) * sim::kHandwheelCountsPerDetent);
  EXPECT_EQ(twin.at[kLast + 1 + 4 * size_t(kX) + 2], 30 - 100);
  EXPECT_EQ(twin.at[kLast + 1 + 4 * size_t(kZ) + 2], -4);
}

}  // namespace
}  // namespace mc::test
