// The machine I/O of the Verilated board top, through its pins and its
// link (tests/board_harness.hpp): the handwheel jog moves the selected axis
// exactly the detents times the increment, and a probe edge latches every
// axis's position in one clock and stops the interpolator in the next.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "Vmotioncore_icebreaker___024root.h"
#include "board_harness.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::test {
namespace {

uint16_t ax(int a, uint16_t off) {
  return br::axis(a, off);
}

#define BOARD(name) (tb.pins().rootp->motioncore_icebreaker__DOT__u_board__DOT__##name)
#define DEC_POS(a) BOARD(u_core__DOT____Vcellout__g_enc__BRA__##a##__KET____DOT__u_dec__pos_o)
#define CMD(a) BOARD(u_core__DOT__u_interp__DOT__g_pos__BRA__##a##__KET____DOT__p)

// Turns the handwheel by `counts` quadrature counts, an edge every 30 clocks.
void turn(BoardTb& tb, int& phase, int counts) {
  auto& p = tb.pins();
  for (int i = 0; i < std::abs(counts); ++i) {
    phase = (phase + (counts > 0 ? 1 : 3)) % 4;
    p.HW_A = phase == 1 || phase == 2;
    p.HW_B = phase >= 2;
    tb.run(30);
  }
}

TEST(BoardIoRtl, HundredHandwheelDetentsAtTimesTenMoveTheAxisAThousandCounts) {
  BoardTb tb;
  tb.write(br::WDOG, (1u << 24) - 1);
  tb.write(br::CTRL, 1u << bb::C_ARM);
  for (int axis : {1, 2}) {
    const int32_t before = int32_t(tb.read(ax(axis, br::AX_CMD)));
    // Axis selected, x10, a count every 2 x 16 clocks.
    tb.write(br::MPG,
             1u << bb::M_ON | uint32_t(axis) << bb::M_AXIS_LSB | 1u << bb::M_STEP_LSB | 2u << bb::M_RATE_LSB);
    int phase = 0;
    turn(tb, phase, 4 * 100);  // 100 detents of four counts
    tb.run(1000 * 32 + 2000);
    EXPECT_EQ(int32_t(tb.read(ax(axis, br::AX_CMD))) - before, 1000) << "axis " << axis;
    EXPECT_EQ(tb.read(br::IO_STAT) >> bb::IOS_MPG_PEND_LSB, 0u) << "nothing left pending";
    // Back by 30 detents at x1 (M_STEP 0).
    tb.write(br::MPG, 1u << bb::M_ON | uint32_t(axis) << bb::M_AXIS_LSB | 2u << bb::M_RATE_LSB);
    turn(tb, phase, -4 * 30);
    tb.run(30 * 32 + 2000);
    EXPECT_EQ(int32_t(tb.read(ax(axis, br::AX_CMD))) - before, 970) << "axis " << axis;
    tb.write(br::MPG, 0);
  }
  EXPECT_EQ(int32_t(tb.read(ax(0, br::AX_CMD))), 0) << "an axis not selected stays";
  EXPECT_EQ(tb.read(br::FAULT), 0u);
}

TEST(BoardIoRtl, AProbeEdgeLatchesEveryAxisInOneClockAndStopsTheInterpolator) {
  BoardTb tb;
  auto& p = tb.pins();
  tb.write(br::WDOG, (1u << 24) - 1);
  // Every axis latches on the probe, and a latch stops the motion.
  tb.write(br::LATCH, bb::L_SRC_PROBE << bb::L_SRC_LSB | bb::L_SRC_PROBE << (bb::L_SRC_LSB + 2) |
                          bb::L_SRC_PROBE << (bb::L_SRC_LSB + 4) | 1u << bb::L_STOP);
  for (int a = 0; a < 3; ++a) tb.write(ax(a, br::AX_IDX), 1u << bb::X_ARM);
  // A long line on all three axes (the command moves; the encoders are
  // moved by hand below, each at its own rate, so the positions differ).
  std::vector<seg::Words> segs = {seg::pack(host::plan_line({0, 0, 0}, {20000, -15000, 9000}, 20000).seg)};
  segs.back()[seg::W_HDR] |= 1u << seg::H_LAST;
  auto r = tb.transact(hp::segments(tb.next_seq(), segs));
  ASSERT_TRUE(r && r->status == bp::ST_OK);
  tb.write(br::CTRL, 1u << bb::C_ARM);

  int phase[3] = {};
  const int period[3] = {23, 37, 51};
  uint8_t* a_pin[3] = {&p.X_ENC_A, &p.Y_ENC_A, &p.Z_ENC_A};
  uint8_t* b_pin[3] = {&p.X_ENC_B, &p.Y_ENC_B, &p.Z_ENC_B};
  int32_t pos_at_latch[3] = {}, cmd_at_stop[3] = {};
  long latch_clock = -1, stop_clock = -1;
  for (long c = 0; c < 400'000 && stop_clock < 0; ++c) {
    for (int a = 0; a < 3; ++a)
      if (c % period[a] == 0) {
        phase[a] = (phase[a] + (a == 1 ? 3 : 1)) % 4;
        *a_pin[a] = phase[a] == 1 || phase[a] == 2;
        *b_pin[a] = phase[a] >= 2;
      }
    if (c == 200'000) p.PROBE = 1;  // the probe touches, mid-move
    tb.clock();
    const uint8_t latch = BOARD(io_latch);
    if (latch != 0) {
      ASSERT_EQ(latch, 7) << "every axis in the same clock";
      ASSERT_LT(latch_clock, 0) << "one strobe per touch";
      latch_clock = c;
      // The decoders take the strobe at the next edge: the positions then.
      pos_at_latch[0] = int32_t(DEC_POS(0));
      pos_at_latch[1] = int32_t(DEC_POS(1));
      pos_at_latch[2] = int32_t(DEC_POS(2));
    }
    if (BOARD(io_stop)) {
      stop_clock = c;
      cmd_at_stop[0] = int32_t(CMD(0));
      cmd_at_stop[1] = int32_t(CMD(1));
      cmd_at_stop[2] = int32_t(CMD(2));
    }
  }
  ASSERT_GE(latch_clock, 200'000) << "the probe never latched";
  EXPECT_EQ(stop_clock, latch_clock) << "the stop comes with the latch";
  EXPECT_LE(latch_clock - 200'000, 2 + 4 + 1) << "synchronizer, filter and strobe";
  // The command holds from the clock after the stop on.
  tb.clock();
  const int32_t held[3] = {int32_t(CMD(0)), int32_t(CMD(1)), int32_t(CMD(2))};
  tb.run(20'000);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(std::abs(held[a] - cmd_at_stop[a]), 1) << "axis " << a << ": at most the clock in flight";
    EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_CMD))), held[a]) << "axis " << a << " moved on";
    EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_IDX))), pos_at_latch[a]) << "axis " << a;
    EXPECT_NE(pos_at_latch[a], 0) << "axis " << a << ": the encoders moved";
  }
  EXPECT_NE(pos_at_latch[0], pos_at_latch[1]);
  EXPECT_EQ(tb.read(br::IP_STAT) & 0x3FF, 0u) << "the queue was flushed";
  EXPECT_FALSE(tb.read(br::IP_STAT) & (1u << bb::IS_BUSY));
  EXPECT_TRUE(tb.read(br::IO_STAT) >> bb::IOS_PROBE & 1) << "the probe reads active";
}

}  // namespace
}  // namespace mc::test
