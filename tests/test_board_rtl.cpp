// The board top, Verilated, with a host speaking the protocol bit by bit on
// its UART pins (tests/board_harness.hpp): register access, bad frames,
// duplicates, the watchdog, every fault source, telemetry against the PID
// twin, and segments running through the interpolator into the PID.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <random>

#include "board_harness.hpp"
#include "hls/pid_core.hpp"
#include "host/link/board_capture.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::test {
namespace {

uint16_t ax(int a, uint16_t off) {
  return br::axis(a, off);
}

TEST(BoardRtl, IdentityAndRegisterRoundTrips) {
  BoardTb tb;
  EXPECT_EQ(tb.read(br::ID), bb::ID_MAGIC | bp::VERSION);
  // The Verilated board: three axes, a step generator on each
  // (MC_VBOARD_STEPPERS), the loops and the handwheel.
  const uint32_t info = tb.read(br::INFO);
  EXPECT_EQ(info, 3u | 9u << bb::INFO_FIFO_AW_LSB | uint32_t(bp::VERSION) << bb::INFO_VERSION_LSB |
                      uint32_t(MC_VBOARD_STEPPERS) << 16 | 1u << 19 | 1u << 20);
  EXPECT_EQ(bb::info_steppers(info), MC_VBOARD_STEPPERS);
  EXPECT_TRUE(bb::info_servo(info));
  EXPECT_TRUE(bb::info_handwheel(info));
  EXPECT_EQ(tb.read(br::CLK_HZ), uint32_t(kClkHz));
  EXPECT_EQ(tb.read(br::BAUD), uint32_t(kBaud));
  // Reset values of the writable registers.
  EXPECT_EQ(tb.read(br::WDOG), board::wdog_default(uint32_t(kClkHz)));
  EXPECT_EQ(tb.read(br::SAFETY), bb::SAFETY_DEFAULT);
  EXPECT_EQ(tb.read(br::FAULT), 0u);
  EXPECT_EQ(tb.read(br::STATUS) & (1u << bb::ST_ARMED), 0u) << "the drives must start disarmed";

  std::mt19937 rng(7);
  for (uint16_t a : {br::WDOG, br::TLM, br::IP_SET_X, br::IP_SET_Y, br::IP_SET_Z, br::HW_CFG}) {
    const uint32_t v = uint32_t(rng());
    tb.write(a, v);
    EXPECT_EQ(tb.read(a), v) << std::hex << a;
  }
  tb.write(br::TLM, 0);
  for (int a = 0; a < 3; ++a)
    for (uint16_t off : {br::AX_ENC_CFG, br::AX_FERR}) {
      const uint32_t v = uint32_t(rng() & 0xFFFF);
      tb.write(ax(a, off), v);
      EXPECT_EQ(tb.read(ax(a, off)), v);
    }
  // PID registers pass through to pid_core.
  tb.write(pid_reg::addr(1, pid_reg::KP), 0x05123456);
  EXPECT_EQ(tb.read(pid_reg::addr(1, pid_reg::KP)), 0x05123456u);
  EXPECT_EQ(tb.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_NAXES)), 3u);
  // The encoders count from power-up: POS and HW_POS are read-only (the
  // host keeps offsets), a write is refused and changes nothing.
  for (uint16_t r : {ax(2, br::AX_POS), br::HW_POS}) {
    auto w = tb.transact(hp::write(tb.next_seq(), r, 12345));
    ASSERT_TRUE(w);
    EXPECT_EQ(w->status, bp::ST_BAD_REG) << std::hex << r;
    tb.run(200);
    EXPECT_EQ(tb.read(r), 0u) << std::hex << r;
  }
}

TEST(BoardRtl, RefusedCommandsAreCountedAndNotApplied) {
  BoardTb tb;
  const uint32_t wdog = tb.read(br::WDOG);
  struct Case {
    hp::Frame f;
    uint8_t status;
  };
  std::vector<Case> cases = {
      {hp::read(tb.next_seq(), 0x0180), bp::ST_BAD_REG},                   // past the globals
      {hp::read(tb.next_seq(), br::axis(3, br::AX_POS)), bp::ST_BAD_REG},  // no fourth axis
      {hp::read(tb.next_seq(), br::axis(0, br::AX_END)), bp::ST_BAD_REG},
      {hp::read(tb.next_seq(), 0x7000), bp::ST_BAD_REG},
      {hp::read(tb.next_seq(), pid_reg::addr(3, pid_reg::KP)), bp::ST_BAD_REG},
      {hp::write(tb.next_seq(), br::ID, 1), bp::ST_BAD_REG},  // read-only
      {hp::write(tb.next_seq(), br::axis(0, br::AX_CMD), 1), bp::ST_BAD_REG},
      {hp::Frame{tb.next_seq(), bp::CMD_READ, {0x07, 0x01, 0x00}}, bp::ST_BAD_LEN},
      {hp::Frame{tb.next_seq(), bp::CMD_WRITE, {0x07, 0x01, 0, 0, 0}}, bp::ST_BAD_LEN},
      {hp::Frame{tb.next_seq(), bp::CMD_SEG, hp::Bytes(36, 0)}, bp::ST_BAD_LEN},
      {hp::Frame{tb.next_seq(), 0x42, {}}, bp::ST_BAD_CMD},
  };
  for (const auto& c : cases) {
    auto r = tb.transact(c.f);
    ASSERT_TRUE(r) << "no reply to cmd " << int(c.f.cmd);
    EXPECT_EQ(r->status, c.status) << "cmd " << int(c.f.cmd);
  }
  EXPECT_EQ(tb.read(br::LINK_CMD) & 0xFFFF, cases.size());
  EXPECT_EQ(tb.read(br::WDOG), wdog);
  EXPECT_EQ(tb.read(br::IP_STAT) & 0x3FF, 0u);
}

TEST(BoardRtl, BadFramesAreDroppedAndCounted) {
  BoardTb tb;
  const uint32_t wdog0 = tb.read(br::WDOG);
  std::mt19937 rng(11);
  int crc_bad = 0, framing = 0, junk = 0;
  // A corrupted byte anywhere after SYNC: no reply, nothing applied.
  for (int i = 1; i < 12; ++i) {
    auto b = hp::encode(hp::write(tb.next_seq(), br::WDOG, 1000));
    if (i == 1) continue;  // LEN: changes the framing, tested below
    b[size_t(i)] ^= uint8_t(1 + rng() % 255);
    tb.send_raw(b);
    tb.run(kByteTimeout + 200);  // a frame cut short by the change ends by timeout
    ++crc_bad;
  }
  // Truncated frames: the board waits BYTE_TIMEOUT_US, then drops them.
  for (int cut = 1; cut < 12; ++cut) {
    auto b = hp::encode(hp::write(tb.next_seq(), br::WDOG, 2000));
    b.resize(size_t(cut));
    tb.send_raw(b);
    tb.run(kByteTimeout + 200);
    if (cut > 1)
      ++framing;  // a lone SYNC is still waiting for LEN
    else
      ++framing;
  }
  // LEN beyond MAX_LEN.
  tb.send_raw({bp::SYNC, uint8_t(bp::MAX_LEN + 1), 0, 0});
  tb.run(kByteTimeout + 200);
  ++framing;
  junk += 2;  // the hunt for SYNC resumes right after LEN
  // Garbage without SYNC.
  hp::Bytes g;
  for (int i = 0; i < 50; ++i) {
    uint8_t x = uint8_t(rng());
    if (x == bp::SYNC) x = 0;
    g.push_back(x);
  }
  tb.send_raw(g);
  junk += int(g.size());
  tb.run(200);
  EXPECT_TRUE(tb.telemetry().empty());
  EXPECT_EQ(tb.read(br::WDOG), wdog0) << "a bad frame was applied";
  const uint32_t link = tb.read(br::LINK_CRC);
  // Corrupting SEQ, CMD, payload or CRC bytes always breaks the CRC check.
  // (A corrupted byte that turns into a SYNC is not special: SYNC is only
  // looked for between frames.)
  EXPECT_EQ(int(link & 0xFFFF), crc_bad);
  EXPECT_EQ(int(link >> 16), framing);
  EXPECT_EQ(int(tb.read(br::LINK_JUNK)), junk);
  // The link still works.
  tb.write(br::WDOG, 4321);
  EXPECT_EQ(tb.read(br::WDOG), 4321u);
}

// The link counters saturate at 0xFFFF, counting every event on the way,
// though a byte arrives every 120 clocks while the telemetry walker and the
// register reads compete for the RAM the counters live in.
TEST(BoardRtl, LinkCountersSaturate) {
  BoardTb tb;
  tb.write(br::TLM, 1u | 1u << bb::T_AXES_LSB);  // the walker's reads and a frame every sample
  const hp::Bytes junk(30000, 0x00);
  tb.send_raw(junk);
  EXPECT_EQ(tb.read(br::LINK_JUNK), 30000u);
  tb.send_raw(junk);
  tb.send_raw(hp::Bytes(5536, 0x00));
  EXPECT_EQ(tb.read(br::LINK_JUNK), 65535u);
  tb.send_raw(hp::Bytes(10, 0x00));
  EXPECT_EQ(tb.read(br::LINK_JUNK), 65535u);
  EXPECT_EQ(tb.read(br::LINK_CRC), 0u) << "a neighbouring counter moved";
}

// Counter events arriving while register reads use the same RAM (junk bytes
// and bad-CRC frames right behind each read, telemetry every sample): every
// event counts once, in its own counter.
TEST(BoardRtl, LinkCountersStayExactUnderReads) {
  BoardTb tb;
  tb.write(br::TLM, 1u | 1u << bb::T_AXES_LSB);
  hp::Bytes bad = hp::encode(hp::read(200, br::ID));
  bad.back() ^= 0x5A;  // a wrong CRC
  uint32_t junk = 0, crc_bad = 0, last = 0;
  for (int i = 0; i < 60; ++i) {
    hp::Bytes trailing(size_t(1 + i % 7), 0x00);
    if (i % 3 == 0) trailing.insert(trailing.end(), bad.begin(), bad.end());
    auto r = tb.transact(hp::read(tb.next_seq(), br::LINK_JUNK), kReplyTimeout, trailing);
    ASSERT_TRUE(r);
    EXPECT_GE(r->value, last);
    EXPECT_LE(r->value, junk + uint32_t(trailing.size()));
    last = r->value;
    junk += uint32_t(1 + i % 7);
    crc_bad += i % 3 == 0;
  }
  tb.run(5000);
  tb.write(br::TLM, 0);
  EXPECT_EQ(tb.read(br::LINK_JUNK), junk);
  const uint32_t link = tb.read(br::LINK_CRC);
  EXPECT_EQ(link & 0xFFFF, crc_bad);
  EXPECT_EQ(link >> 16, 0u) << "no framing error";
  EXPECT_EQ(tb.read(br::LINK_CMD), 0u) << "nothing refused, no duplicate";
}

// Three dwell segments of a long duration: the first is loaded into the
// interpolator, two stay queued.
std::vector<seg::Words> dwells(int n) {
  std::vector<seg::Words> v;
  for (int i = 0; i < n; ++i) v.push_back(seg::pack(host::plan_dwell({0, 0, 0}, 1.0).seg));
  return v;
}

TEST(BoardRtl, DuplicateFrameIsAnsweredButNotAppliedTwice) {
  BoardTb tb;
  const auto req = hp::segments(tb.next_seq(), dwells(3));
  auto r1 = tb.transact(req);
  ASSERT_TRUE(r1);
  EXPECT_EQ(r1->status, bp::ST_OK);
  // The host missed the reply and sends the very same frame again.
  auto r2 = tb.transact(req);
  ASSERT_TRUE(r2);
  EXPECT_EQ(r2->status, bp::ST_DUP);
  tb.run(100);
  // One segment loaded into the interpolator, two queued: three, not six.
  EXPECT_EQ(tb.read(br::IP_STAT) & 0x3FF, 2u * seg::SEG_WORDS);
  // Same for a write: answered, counted, not applied.
  const auto w = hp::write(tb.next_seq(), br::IP_SET_X, 5);
  EXPECT_EQ(tb.transact(w)->status, bp::ST_OK);
  tb.write(br::IP_SET_X, 6);
  EXPECT_EQ(tb.transact(w)->status, bp::ST_OK) << "not the last SEQ any more: a new command";
  EXPECT_EQ(tb.transact(w)->status, bp::ST_DUP);
  EXPECT_EQ(tb.read(br::IP_SET_X), 5u);
  EXPECT_EQ(tb.read(br::LINK_CMD) >> 16, 2u);
  // PING starts a session: the last SEQ is forgotten.
  const auto pong = tb.transact(hp::ping(0));
  ASSERT_TRUE(pong);
  EXPECT_EQ(pong->status, bp::ST_OK);
  EXPECT_EQ(pong->value, bb::ID_MAGIC | bp::VERSION) << "PING answers with ID";
  EXPECT_EQ(tb.transact(w)->status, bp::ST_OK);
}

// A segment frame refused FULL stays refused: a copy of it (a retransmission
// whose reply the host may read late, instead of the first one's) gets FULL
// even when the queue has room by then, so that no copy is queued behind the
// host's back; the same segments in a new request are queued.
TEST(BoardRtl, CopiesOfAFullFrameAreRefusedFullToo) {
  BoardTb tb;
  tb.write(br::CTRL, 1u << bb::C_ARM);  // dwells run only while armed
  const std::vector<seg::Words> six(6, seg::pack(host::plan_dwell({0, 0, 0}, 5e-3).seg));
  for (int i = 0; i < 30; ++i) {
    const auto req = hp::segments(tb.next_seq(), six);
    const auto r = tb.transact(req);
    ASSERT_TRUE(r);
    if (r->status != bp::ST_FULL) continue;
    const uint32_t cmd0 = tb.read(br::LINK_CMD);
    // A read moved the last SEQ: refuse the frame again, then wait, with no
    // frame on the line, until six dwells have run and left room for it.
    const auto req2 = hp::segments(tb.next_seq(), six);
    const auto r2 = tb.transact(req2);
    ASSERT_TRUE(r2);
    ASSERT_EQ(r2->status, bp::ST_FULL);
    tb.run(long(12e6 * 40e-3));
    const auto copy = tb.transact(req2);
    ASSERT_TRUE(copy);
    EXPECT_EQ(copy->status, bp::ST_FULL) << "a copy of a refused frame is refused, room or not";
    const uint32_t queued = tb.read(br::IP_STAT) & 0x3FF;
    EXPECT_LE(queued + 6u * seg::SEG_WORDS, 512u) << "the queue had room for the copy";
    const uint32_t cmd1 = tb.read(br::LINK_CMD);
    EXPECT_EQ((cmd1 & 0xFFFF) - (cmd0 & 0xFFFF), 2u) << "the refusal and its copy count as refused";
    EXPECT_EQ(cmd1 >> 16, cmd0 >> 16) << "not as duplicates";
    // The same segments in a new request: queued.
    const auto fresh = tb.transact(hp::segments(tb.next_seq(), six));
    ASSERT_TRUE(fresh);
    EXPECT_EQ(fresh->status, bp::ST_OK);
    EXPECT_GT(tb.read(br::IP_STAT) & 0x3FF, queued) << "queued (a dwell may have ended meanwhile)";
    return;
  }
  FAIL() << "the queue never filled";
}

// Arms the board with an override drive on axis 0, so the DRV_EN pin shows
// whether the drive is allowed.
void arm_with_drive(BoardTb& tb) {
  tb.write(ax(0, br::AX_DRV), 1u << bb::D_OVR | 0x4000);
  tb.write(br::CTRL, 1u << bb::C_ARM);
  tb.run(10);
  ASSERT_TRUE(tb.read(br::STATUS) & (1u << bb::ST_ARMED));
  ASSERT_TRUE(tb.pins().DRV_EN);
}

void expect_fault_then_clear(BoardTb& tb, uint32_t bit, const char* what) {
  SCOPED_TRACE(what);
  EXPECT_FALSE(tb.pins().DRV_EN) << "the drive must be off";
  EXPECT_EQ(tb.read(br::FAULT), bit);
  EXPECT_FALSE(tb.read(br::STATUS) & (1u << bb::ST_ARMED));
  tb.write(br::CTRL, 1u << bb::C_ARM);  // refused while the fault is latched
  EXPECT_FALSE(tb.pins().DRV_EN);
}

TEST(BoardRtl, WatchdogDisablesTheDrivesWhenTheHostGoesQuiet) {
  BoardTb tb;
  const uint32_t period = 30000;
  tb.write(br::WDOG, period);
  arm_with_drive(tb);
  // Frames keep it alive.
  for (int i = 0; i < 5; ++i) {
    tb.run(period / 2);
    tb.transact(hp::ping(tb.next_seq()));
  }
  EXPECT_TRUE(tb.pins().DRV_EN);
  EXPECT_EQ(tb.read(br::FAULT), 0u);
  // Quiet: the drive goes off within the period.
  long n = 0;
  while (tb.pins().DRV_EN && n < 2L * period) {
    tb.clock();
    ++n;
  }
  EXPECT_LE(n, long(period));
  EXPECT_GT(n, long(period) - 2000);
  expect_fault_then_clear(tb, 1u << bb::F_WDOG, "watchdog");
  tb.write(br::FAULT, 1u << bb::F_WDOG);
  EXPECT_EQ(tb.read(br::FAULT), 0u);
  EXPECT_FALSE(tb.pins().DRV_EN) << "clearing a fault does not re-arm";
  tb.write(br::CTRL, 1u << bb::C_ARM);
  tb.run(5);
  EXPECT_TRUE(tb.pins().DRV_EN);
}

TEST(BoardRtl, EveryFaultSourceLatchesAndClears) {
  BoardTb tb;
  tb.write(br::WDOG, (1u << 24) - 1);
  struct Src {
    const char* name;
    uint32_t bit;
    std::function<void(bool)> set;
  };
  auto& p = tb.pins();
  std::vector<Src> srcs = {
      {"e-stop", 1u << bb::F_ESTOP, [&](bool on) { p.ESTOP = on; }},
      {"button", 1u << bb::F_ESTOP, [&](bool on) { p.BTN_N = !on; }},
      {"limit X", 1u << (bb::F_LIMIT_LSB + 0), [&](bool on) { p.X_LIM = on; }},
      {"limit Y", 1u << (bb::F_LIMIT_LSB + 1), [&](bool on) { p.Y_LIM = on; }},
      {"limit Z", 1u << (bb::F_LIMIT_LSB + 2), [&](bool on) { p.Z_LIM = on; }},
  };
  for (auto& s : srcs) {
    arm_with_drive(tb);
    s.set(true);
    tb.run(10);
    expect_fault_then_clear(tb, s.bit, s.name);
    tb.write(br::FAULT, s.bit);  // still active: latches again
    EXPECT_EQ(tb.read(br::FAULT), s.bit) << s.name;
    s.set(false);
    tb.run(10);
    tb.write(br::FAULT, s.bit);
    EXPECT_EQ(tb.read(br::FAULT), 0u) << s.name;
  }
  // A disabled limit input is ignored.
  tb.write(br::SAFETY, bb::SAFETY_DEFAULT & ~(1u << (bb::S_LIM_EN_LSB + 1)));
  arm_with_drive(tb);
  p.Y_LIM = 1;
  tb.run(10);
  EXPECT_TRUE(p.DRV_EN);
  p.Y_LIM = 0;
  tb.write(br::SAFETY, bb::SAFETY_DEFAULT);

  // Encoder: A and B change in the same clock.
  arm_with_drive(tb);
  p.Y_ENC_A = 1;
  p.Y_ENC_B = 1;
  tb.run(10);
  expect_fault_then_clear(tb, 1u << (bb::F_ENC_LSB + 1), "encoder Y");
  EXPECT_TRUE(tb.read(ax(1, br::AX_ENC_STAT)) & (1u << bb::ES_ERR));
  tb.write(br::FAULT, 1u << (bb::F_ENC_LSB + 1));  // also clears the decoder's flag
  EXPECT_EQ(tb.read(br::FAULT), 0u);
  EXPECT_FALSE(tb.read(ax(1, br::AX_ENC_STAT)) & (1u << bb::ES_ERR));

  // Following error: command 100 counts away from the encoder.
  tb.write(ax(2, br::AX_FERR), 100);
  tb.write(br::IP_SET_Z, 100);
  tb.write(br::IP_CTRL, 1u << bb::I_SET);
  tb.run(200);
  arm_with_drive(tb);  // |100| is not above 100
  tb.write(br::IP_SET_Z, uint32_t(-101));
  tb.write(br::IP_CTRL, 1u << bb::I_SET);
  tb.run(200);
  expect_fault_then_clear(tb, 1u << (bb::F_FERR_LSB + 2), "following error Z");
  tb.write(ax(2, br::AX_FERR), 0);  // off
  tb.write(br::FAULT, 1u << (bb::F_FERR_LSB + 2));
  tb.run(200);
  EXPECT_EQ(tb.read(br::FAULT), 0u);
}

// IP_CTRL.set loads every axis's command from IP_SET_X..Z (read from the
// register file's RAM one axis at a time); a write of IP_SET alone moves
// nothing.
TEST(BoardRtl, IpSetLoadsEachAxisCommand) {
  BoardTb tb;
  const int32_t v[3] = {123456, -7, int32_t(0x80000001u)};
  for (int a = 0; a < 3; ++a) tb.write(uint16_t(br::IP_SET_X + a), uint32_t(v[a]));
  tb.run(200);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(tb.read(ax(a, br::AX_CMD)), 0u) << a;
  tb.write(br::IP_CTRL, 1u << bb::I_SET);
  tb.run(200);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_CMD))), v[a]) << a;
    EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_FOLLOW))), v[a]) << a;  // the encoders are at 0
  }
  // FOLLOW saturates: -2^31 + 1 - 2 is below the 32-bit range. Z's encoder
  // moves two counts forward (AB 00, 10, 11).
  tb.pins().Z_ENC_A = 1;
  tb.run(20);
  tb.pins().Z_ENC_B = 1;
  tb.run(200);
  EXPECT_EQ(tb.read(ax(2, br::AX_POS)), 2u);
  EXPECT_EQ(tb.read(ax(2, br::AX_FOLLOW)), 0x80000000u);
  // Again with new values, and clear in the same write.
  for (int a = 0; a < 3; ++a) tb.write(uint16_t(br::IP_SET_X + a), uint32_t(-v[a] / 2));
  tb.write(br::IP_CTRL, 1u << bb::I_SET | 1u << bb::I_CLR);
  tb.run(200);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_CMD))), -v[a] / 2) << a;
}

// DRV hands an axis's drive to the host: the value reads back and sets the
// PWM duty at once; clearing the override gives the drive back to the PID at
// its next sample (here a disabled PID: 0).
TEST(BoardRtl, DriveOverrideAppliesAndReleases) {
  BoardTb tb;
  auto& p = tb.pins();
  tb.write(br::CTRL, 1u << bb::C_ARM);
  auto duty = [&] {  // PWM high clocks over one 512-clock period
    int hi = 0;
    for (int i = 0; i < 512; ++i) {
      tb.run(1);
      hi += p.Y_PWM;
    }
    return hi;
  };
  for (int16_t v : {int16_t(0x4000), int16_t(-0x2000), int16_t(32767)}) {
    tb.write(ax(1, br::AX_DRV), 1u << bb::D_OVR | uint16_t(v));
    EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), 1u << bb::D_OVR | uint16_t(v));
    EXPECT_TRUE(p.DRV_EN);
    EXPECT_EQ(bool(p.Y_DIR), v < 0);
    EXPECT_NEAR(duty(), std::abs(v) >> 6, 1) << v;
  }
  tb.write(ax(1, br::AX_DRV), 0);
  tb.run(200);  // the next sample
  EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), 0u);
  EXPECT_FALSE(p.DRV_EN);
  EXPECT_EQ(duty(), 0);
}

// The home-switch latch (the index latch, in block RAM, fed by mc_io): IDX
// holds the count at the switch's filtered edge, and with "index clears" the
// count restarts from 0 there. The iCEBreaker has no index pins; the home
// switch is the axis's limit input, its fault disabled while homing.
TEST(BoardRtl, HomeSwitchLatchesThePosition) {
  BoardTb tb;
  auto& p = tb.pins();
  // X's and Y's limits: home switches only.
  tb.write(br::SAFETY, bb::SAFETY_DEFAULT & ~(3u << bb::S_LIM_EN_LSB));
  tb.write(br::LATCH, bb::L_SRC_HOME << bb::L_SRC_LSB | bb::L_SRC_NONE << (bb::L_SRC_LSB + 2) |
                          bb::L_SRC_NONE << (bb::L_SRC_LSB + 4));
  int phase = 0;
  auto move = [&](int steps) {  // quadrature steps on X, 20 clocks each
    for (int i = 0; i < std::abs(steps); ++i) {
      phase = (phase + (steps > 0 ? 1 : 3)) % 4;
      p.X_ENC_A = phase == 1 || phase == 2;
      p.X_ENC_B = phase >= 2;
      tb.run(20);
    }
  };
  auto home = [&] {
    tb.write(ax(0, br::AX_IDX), 1u << bb::X_ARM);
    p.X_LIM = 1;
    p.Y_LIM = 1;  // Y's switch latches nothing: its source is none
    tb.run(20);
    p.X_LIM = 0;
    p.Y_LIM = 0;
    tb.run(200);  // a sample for POS
  };
  move(37);
  home();
  EXPECT_EQ(tb.read(ax(0, br::AX_IDX)), 37u);
  EXPECT_EQ(tb.read(ax(0, br::AX_POS)), 37u);
  EXPECT_EQ(tb.read(br::FAULT), 0u) << "a disabled limit is only a home switch";
  move(-50);
  tb.write(ax(0, br::AX_ENC_CFG), 1u << bb::E_IDX_CLR_EN);
  home();
  EXPECT_EQ(int32_t(tb.read(ax(0, br::AX_IDX))), -13);
  EXPECT_EQ(tb.read(ax(0, br::AX_POS)), 0u) << "the switch cleared the count";
  move(5);
  tb.run(200);
  EXPECT_EQ(tb.read(ax(0, br::AX_POS)), 5u);
  EXPECT_EQ(int32_t(tb.read(ax(0, br::AX_IDX))), -13);
  // A bounce shorter than the filter's four clocks latches nothing.
  tb.write(ax(0, br::AX_IDX), 1u << bb::X_ARM);
  p.X_LIM = 1;
  tb.run(3);
  p.X_LIM = 0;
  tb.run(200);
  EXPECT_EQ(int32_t(tb.read(ax(0, br::AX_IDX))), -13) << "a glitch latched";
  EXPECT_TRUE(tb.read(ax(0, br::AX_ENC_STAT)) >> bb::ES_IDX_ARMED & 1) << "the latch is still armed";
}

// TLM.decim = N: a frame every N-th sample, the first N samples after the
// write, with only the axes asked for; 0 stops them.
TEST(BoardRtl, TelemetryDecimation) {
  BoardTb tb;
  constexpr long kTs = 5000;  // a one-axis frame (27 bytes) fits in a period
  tb.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), kTs);
  for (uint32_t n : {1u, 3u, 7u}) {
    tb.telemetry().clear();
    const uint32_t before = tb.read(br::TLM_HDR) & 0xFFFF;
    tb.write(br::TLM, n | 2u << bb::T_AXES_LSB);  // axis Y only
    tb.run(kTs * 40);
    tb.write(br::TLM, 0);
    auto& f = tb.telemetry();
    ASSERT_GE(f.size(), size_t(40 / n - 2)) << n;
    std::optional<uint16_t> last;
    for (const auto& fr : f) {
      const auto t = hp::parse_telemetry(fr, 2);
      ASSERT_EQ(t.axes.size(), 1u);
      if (last) {
        EXPECT_EQ(uint16_t(t.sample - *last), n) << "decimation " << n;
      }
      last = t.sample;
    }
    // The write's reply leaves within a sample of the write, so the first
    // frame is the N-th or N+1-th sample after the sample count read before.
    const auto first = hp::parse_telemetry(f.front(), 2).sample;
    EXPECT_GE(uint16_t(first - before), n) << n;
    EXPECT_LE(uint16_t(first - before), n + 2) << n;
    tb.run(kTs);  // a frame already prepared still goes out
    tb.telemetry().clear();
    tb.run(kTs * 10);
    EXPECT_TRUE(tb.telemetry().empty()) << "TLM 0 stops the frames";
  }
  // Writing TLM again restarts the count: 3.5 samples into a decimation of 7,
  // the same write puts the next frame 7 samples away, not 3.5.
  tb.write(br::TLM, 7u | 2u << bb::T_AXES_LSB);
  tb.run(kTs * 7 / 2);
  tb.telemetry().clear();
  const uint32_t before = tb.read(br::TLM_HDR) & 0xFFFF;
  tb.write(br::TLM, 7u | 2u << bb::T_AXES_LSB);
  tb.run(kTs * 12);
  ASSERT_FALSE(tb.telemetry().empty());
  EXPECT_GE(uint16_t(hp::parse_telemetry(tb.telemetry().front(), 2).sample - before), 7u);
}

// The line time the host budgets for a frame (board_tx_seconds, behind
// telemetry_decimation) against the board: a frame every sample at Ts =
// that time loses none; at 9 clocks less every other sample is skipped, so
// the figure is neither short nor more than 8 clocks loose.
TEST(BoardRtl, TelemetryFitsTheLineTimeTheHostBudgets) {
  const double frame_s = host::board_tx_seconds(host::telemetry_frame_bytes(1), 1, kClkHz, kBaud);
  const long fit = std::lround(frame_s * kClkHz);
  EXPECT_EQ(host::telemetry_decimation(double(fit) / kClkHz, kClkHz, kBaud, 0), 1u);
  EXPECT_EQ(host::telemetry_decimation(double(fit - 1) / kClkHz, kClkHz, kBaud, 0), 2u);
  for (const long ts : {fit, fit - 9}) {
    BoardTb tb;
    tb.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), uint32_t(ts));
    tb.write(br::TLM, 1u | 1u << bb::T_AXES_LSB);
    tb.run(ts * 4);  // the write's reply is gone
    tb.telemetry().clear();
    tb.run(ts * 200);
    tb.write(br::TLM, 0);
    int gaps = 0, frames = 0;
    std::optional<uint16_t> last;
    for (const auto& fr : tb.telemetry()) {
      const uint16_t n = hp::parse_telemetry(fr, 1).sample;
      if (last && uint16_t(n - *last) != 1) ++gaps;
      last = n;
      ++frames;
    }
    ASSERT_GE(frames, 90) << "Ts " << ts;
    if (ts == fit)
      EXPECT_EQ(gaps, 0) << "a frame every " << ts << " clocks";
    else
      EXPECT_GE(gaps, frames - 2) << "Ts " << ts << " is shorter than a frame: every other sample skipped";
  }
}

// A telemetry frame that waits behind a reply keeps its words when the
// next sample's walk ends first, as it does whenever Ts is shorter than a
// reply (1374 clocks; 1200 is the default 100 us). PINGs at random times,
// at the decimation the host picks: every frame whole, no sample skipped.
TEST(BoardRtl, TelemetryBehindAReplyKeepsItsWords) {
  for (const long ts : {70L, 1200L}) {
    BoardTb tb;
    tb.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), uint32_t(ts));
    const uint32_t decim = host::telemetry_decimation(double(ts) / kClkHz, kClkHz, kBaud, 2);
    tb.write(br::TLM, decim | 1u << bb::T_AXES_LSB);
    tb.run(ts * decim * 2);
    tb.telemetry().clear();
    std::mt19937 rng{uint32_t(ts)};
    for (int i = 0; i < 200; ++i) {
      tb.run(long(rng() % uint32_t(ts * decim * 3)));
      ASSERT_TRUE(tb.transact(hp::ping(tb.next_seq())));
    }
    tb.write(br::TLM, 0);
    int gaps = 0;
    std::optional<uint16_t> last;
    for (const auto& fr : tb.telemetry()) {
      ASSERT_EQ(fr.payload.size(), 20u) << "Ts " << ts << ": a frame of one axis lost its words";
      const uint16_t n = hp::parse_telemetry(fr, 1).sample;
      if (last && uint16_t(n - *last) != decim) ++gaps;
      last = n;
    }
    EXPECT_GT(tb.telemetry().size(), 150u) << "Ts " << ts;
    EXPECT_EQ(gaps, 0) << "Ts " << ts << ", decimation " << decim;
  }
}

// With the PID running: an override holds through samples, and after its
// release the host's last value holds until the PID's next output.
TEST(BoardRtl, DriveOverrideHoldsUntilThePidsNextOutput) {
  BoardTb tb;
  constexpr long kTs = 200000;  // long, so the release lands well inside a period
  const uint32_t ovr = 1u << bb::D_OVR;
  tb.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), kTs);
  tb.write(pid_reg::addr(1, pid_reg::KP), (1u << 22) | (16u << 24));  // 64 per count
  tb.write(pid_reg::addr(1, pid_reg::CTRL), 1);
  tb.write(br::IP_SET_Y, 100);  // the encoder stays at 0: error 100
  tb.write(br::IP_CTRL, 1u << bb::I_SET);
  tb.write(br::CTRL, 1u << bb::C_ARM);
  tb.run(kTs + 100);
  EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), 6400u) << "the PID drives: 64 x 100";
  tb.write(ax(1, br::AX_DRV), ovr | 0x4000);
  tb.run(2 * kTs);
  EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), ovr | 0x4000) << "the samples leave an override alone";
  tb.write(ax(1, br::AX_DRV), 0);
  EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), 0x4000u) << "released: the host's value holds";
  tb.run(kTs);
  EXPECT_EQ(tb.read(ax(1, br::AX_DRV)), 6400u) << "the PID's next output";
}

// The board's decoders filter up to 15 clocks: a longer ENC_CFG length reads
// back as written and acts as 15, never as its low bits (16 would be 0).
// Seen through the count: A and B each pulse high for the same clocks, B
// two clocks behind A, a forward quadrature cycle (+4) if the filter
// passes both pulses and no count if it drops them.
TEST(BoardRtl, EncoderFilterLengthClampsToTheLongestBuilt) {
  BoardTb tb;
  auto& p = tb.pins();
  auto a_pulse_passes = [&](int clocks) {
    const int32_t before = int32_t(tb.read(ax(0, br::AX_POS)));
    p.X_ENC_A = 1;
    tb.run(2);
    p.X_ENC_B = 1;
    tb.run(clocks - 2);
    p.X_ENC_A = 0;
    tb.run(2);
    p.X_ENC_B = 0;
    tb.run(200);  // a sample for POS
    const int32_t moved = int32_t(tb.read(ax(0, br::AX_POS))) - before;
    EXPECT_TRUE(moved == 0 || moved == 4) << moved;
    return moved == 4;
  };
  for (uint32_t len : {15u, 16u, 200u, 255u}) {
    tb.write(ax(0, br::AX_ENC_CFG), len);
    EXPECT_EQ(tb.read(ax(0, br::AX_ENC_CFG)), len);
    EXPECT_FALSE(a_pulse_passes(14)) << "filter " << len;
    EXPECT_TRUE(a_pulse_passes(15)) << "filter " << len;
  }
  tb.write(ax(0, br::AX_ENC_CFG), 13);
  EXPECT_FALSE(a_pulse_passes(12));
  EXPECT_TRUE(a_pulse_passes(13));
}

// Telemetry every sample, compared with the PID twin fed the sampled command
// and feedback; the command comes from segments the host planned and queued,
// run end to end through the interpolator.
TEST(BoardRtl, SegmentsRunIntoThePidAndTelemetryMatchesTheTwin) {
  BoardTb tb;
  constexpr int kTs = 10000;  // cycles: a 3-axis frame (58 bytes) and a reply fit in one period
  tb.write(br::WDOG, (1u << 24) - 1);
  tb.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), kTs);
  PidCore<3> twin;
  twin.reset();
  twin.write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), kTs);
  // Gains: P, I and D on every axis (words: [29:24] shift, [23:0] mantissa).
  const uint32_t words[][2] = {{pid_reg::KP, 0x0C400000},   {pid_reg::KI, 0x10300000},
                               {pid_reg::KD_A, 0x01700000}, {pid_reg::KD_B, 0x0A200000},
                               {pid_reg::OLIM, 20000},      {pid_reg::ILIM, 10000}};
  for (int a = 0; a < 3; ++a) {
    for (const auto& w : words) {
      tb.write(pid_reg::addr(uint8_t(a), uint8_t(w[0])), w[1]);
      twin.write(pid_reg::addr(uint8_t(a), uint8_t(w[0])), w[1]);
    }
    tb.write(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1);
    twin.write(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1);
  }
  tb.write(br::TLM, 1u << bb::T_DECIM_LSB | 7u << bb::T_AXES_LSB);
  tb.run(2 * kTs);
  tb.telemetry().clear();

  // Two lines and a dwell, planned on the host.
  const host::Vec3 p0{0, 0, 0}, p1{300, -120, 40}, p2{100, 80, 40};
  std::vector<seg::Words> segs = {seg::pack(host::plan_line(p0, p1, 20000).seg),
                                  seg::pack(host::plan_line(p1, p2, 30000).seg),
                                  seg::pack(host::plan_dwell(p2, 0.002).seg)};
  segs.back()[seg::W_HDR] |= 1u << seg::H_LAST;
  auto r = tb.transact(hp::segments(tb.next_seq(), segs));
  ASSERT_TRUE(r && r->status == bp::ST_OK);
  tb.write(br::CTRL, 1u << bb::C_ARM);  // the feed runs only while armed

  // Run until the interpolator is idle with all three done, then a little.
  for (int i = 0; i < 200 && (tb.read(br::IP_SEGS) < 3 || (tb.read(br::IP_STAT) & (1u << bb::IS_BUSY))); ++i)
    tb.run(20 * kTs);
  tb.run(3 * kTs);
  EXPECT_EQ(tb.read(br::IP_SEGS), 3u);
  EXPECT_FALSE(tb.read(br::IP_STAT) & (1u << bb::IS_UNDERRUN));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(int32_t(tb.read(ax(a, br::AX_CMD))), p2[size_t(a)]) << "axis " << a;

  // Every telemetry frame: consecutive samples, the twin agrees bit for bit.
  const auto& frames = tb.telemetry();
  ASSERT_GT(frames.size(), 50u);
  int moved = 0, nonzero_u = 0;
  std::optional<uint16_t> last;
  int32_t prev_cmd[3] = {};
  for (const auto& f : frames) {
    const auto t = hp::parse_telemetry(f, 7);
    if (last) {
      ASSERT_EQ(uint16_t(*last + 1), t.sample) << "a telemetry frame was skipped";
    }
    last = t.sample;
    int32_t cmd[3], fb[3];
    for (int a = 0; a < 3; ++a) {
      cmd[a] = t.axes[size_t(a)].cmd;
      fb[a] = t.axes[size_t(a)].pos;
      EXPECT_EQ(fb[a], 0) << "the encoders do not move";
      EXPECT_LE(std::abs(cmd[a] - prev_cmd[a]), kTs) << "the command jumped";
      moved += cmd[a] != prev_cmd[a];
      prev_cmd[a] = cmd[a];
    }
    twin.sample(cmd, fb);
    for (int a = 0; a < 3; ++a) {
      const auto& s = t.axes[size_t(a)];
      ASSERT_EQ(s.u, twin.u(a)) << "sample " << t.sample << " axis " << a;
      ASSERT_EQ(s.err, twin.err(a)) << "sample " << t.sample << " axis " << a;
      ASSERT_EQ(s.sat, twin.sat(a)) << "sample " << t.sample << " axis " << a;
      EXPECT_TRUE(s.pid_en);
      nonzero_u += s.u != 0;
    }
  }
  EXPECT_GT(moved, 20);
  EXPECT_GT(nonzero_u, 20);
  EXPECT_EQ(tb.host_rx_stats().crc, 0u);
}

}  // namespace
}  // namespace mc::test
