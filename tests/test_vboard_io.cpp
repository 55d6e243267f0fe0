// The virtual board's machine I/O (issue 17): home switches at their
// configured positions and a probe on a tilted, bowed workpiece, both with
// contact bounce, seen and latched by the board as a real one would; the
// spindle and coolant outputs recorded with the spindle's duty counted
// clock by clock; and the twin and the Verilated board giving the same
// record. The machine is configs/stepper_router.toml: open-loop steppers
// follow the command step for step, so where the table is, is known.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "hls/board_regs.hpp"
#include "host/link/board_link.hpp"
#include "host/machine/workpiece.hpp"
#include "host/motion/board_run.hpp"
#include "host/motion/interp_plan.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/contact.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;
namespace bb = board::bits;
using sim::VirtualBoard;

// As tests/test_vboard_stepper.cpp: 2 us pulses, 1 us of direction setup.
constexpr uint32_t kPulseClocks = 24, kSetupClocks = 12;
constexpr int kX = 0, kY = 1, kZ = 2;

machine::MachineConfig stepper_router() {
  return machine::load_machine(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml");
}

// A tilted, bowed, rough plate under the stepper router's tool.
machine::WorkpieceConfig plate() {
  return {.min_x_m = -0.05,
          .min_y_m = -0.04,
          .max_x_m = 0.1,
          .max_y_m = 0.08,
          .top_z_m = -0.004,
          .tilt_x = 0.008,
          .tilt_y = -0.005,
          .bow_m = 0.0004,
          .noise_m = 3e-6,
          .noise_seed = 5};
}

struct Rig {
  // start_m: each axis's table position at power-up (VirtualBoard::start_at).
  Rig(const machine::MachineConfig& m, const std::array<double, 3>& start_m, uint32_t seed = 0,
      sim::BoardEngine e = sim::BoardEngine::Twin)
      : cfg(m), board(m, seed, e), stream(board), link(stream) {
    for (int a = 0; a < 3; ++a) board.start_at(a, start_m[size_t(a)]);
    link.connect();
    link.write(br::WDOG, (1u << 24) - 1);
  }
  // Open-loop steppers on every axis, armed.
  void arm() {
    link.write(br::STEP_CFG,
               7u << bb::SC_STEPPER_LSB | kPulseClocks << bb::SC_PW_LSB | kSetupClocks << bb::SC_SETUP_LSB);
    link.write(br::CTRL, 1u << bb::C_ARM);
  }
  // LATCH sources (L_SRC_* per axis) and stop; every axis's latch armed.
  void latch(const std::array<uint32_t, 3>& src, bool stop) {
    uint32_t v = stop ? 1u << bb::L_STOP : 0;
    for (int a = 0; a < 3; ++a) v |= src[size_t(a)] << (bb::L_SRC_LSB + 2 * a);
    link.write(br::LATCH, v);
    for (int a = 0; a < 3; ++a) link.write(br::axis(a, br::AX_IDX), 1u << bb::X_ARM);
  }
  // A straight move at feed (m/s along the path), queued; then board time
  // passes until the interpolator stands (at the end, or where a latch
  // with LATCH.stop flushed the rest). False: still busy after max_s of
  // board time.
  bool move(const host::Vec3& to, double feed_m_s, double max_s = 5) {
    const auto segs = host::plan_move(at, to, feed_m_s * machine::counts_per_m(cfg.axes[0]), cfg.clock_hz);
    at = to;
    size_t sent = 0;
    while (sent < segs.size()) {
      const size_t before = sent;
      sent = host::send_segments(link, segs, sent);
      if (sent == before) link.poll(std::chrono::milliseconds(1));
    }
    for (const double end = board.board_seconds() + max_s; board.board_seconds() < end;) {
      const uint32_t ip = link.read(br::IP_STAT);
      if (!(ip >> bb::IS_BUSY & 1) && (ip & 0xFFFF) == 0) return true;
      link.poll(std::chrono::milliseconds(1));
    }
    return false;
  }
  int32_t reg(int a, uint16_t off) { return int32_t(link.read(br::axis(a, off))); }
  bool latched(int a) { return link.read(br::axis(a, br::AX_ENC_STAT)) >> bb::ES_IDX_SEEN & 1; }

  machine::MachineConfig cfg;
  VirtualBoard board;
  sim::BoardStream stream;
  host::BoardLink link;
  host::Vec3 at{0, 0, 0};
};

int64_t counts(const machine::AxisConfig& a, double m) {
  return std::llround(m * machine::counts_per_m(a));
}

// The contact alone: the pin follows a crossing at once, chatters for
// exactly the bounce time, settles at the true state; a seed gives its own
// chatter, the same every time; no bounce time, one clean edge.
std::vector<bool> crossing(uint32_t bounce_steps, uint64_t seed, sim::Contact* out = nullptr) {
  sim::Contact c(bounce_steps, seed);
  c.settle(false);
  std::vector<bool> pins;
  for (int i = 0; i < 3; ++i) c.step(false);
  EXPECT_EQ(c.edges(), 0u);
  c.step(true);
  pins.push_back(c.pin());
  while (c.bouncing()) {
    c.step(true);
    pins.push_back(c.pin());
  }
  if (out) *out = c;
  return pins;
}

TEST(VBoardIo, AContactBouncesForItsTimeThenSettles) {
  sim::Contact c;
  const std::vector<bool> a = crossing(500, 42, &c);
  EXPECT_TRUE(a.front()) << "the first touch shows at once";
  EXPECT_EQ(a.size(), 501u) << "settled 500 steps after the crossing";
  EXPECT_TRUE(a.back());
  EXPECT_GE(c.edges(), 5u);
  EXPECT_EQ(c.edges() % 2, 1u) << "open to closed";
  const uint64_t edges = c.edges();
  for (int i = 0; i < 1000; ++i) c.step(true);
  EXPECT_EQ(c.edges(), edges) << "settled stays settled";
  EXPECT_EQ(crossing(500, 42), a);
  EXPECT_NE(crossing(500, 43), a);
  sim::Contact clean;
  EXPECT_EQ(crossing(0, 42, &clean), std::vector<bool>{true});
  EXPECT_EQ(clean.edges(), 1u);
}

// X driven through its home switch at the locate speed, the home switch as
// X's latch source: the board latches the count at which the switch truly
// closes. The table starts at an odd place short of the switch, so a
// switch placed from the wrong frame closes elsewhere or never; bounce
// that closed the contact before the crossing would latch early.
TEST(VBoardIo, TheHomeSwitchLatchesWhereItCloses) {
  const machine::MachineConfig m = stepper_router();
  const machine::AxisConfig& x = m.axes[kX];
  const machine::HomeConfig& h = *x.home;  // 0.145 m, closed at >= it
  ASSERT_EQ(h.direction, 1);
  const double start = h.switch_m - 0.0002137;
  Rig r(m, {start, 0, 0}, 11);
  EXPECT_FALSE(r.board.limit_pin(kX));
  // The limit input is the switch: with it enabled (SAFETY's default) the
  // crossing would trip LIMIT, so it is off while homing, as a homing cycle does.
  r.link.write(br::SAFETY, 1u << bb::S_ESTOP_EN);
  r.arm();
  r.latch({bb::L_SRC_HOME, bb::L_SRC_NONE, bb::L_SRC_NONE}, false);
  const int64_t to = counts(x, 0.0005);
  ASSERT_TRUE(r.move({to, 0, 0}, h.locate_m_s));

  // POS counts from power-up, not from the frame's 0.
  EXPECT_EQ(r.reg(kX, br::AX_POS), to);
  ASSERT_TRUE(r.latched(kX)) << "the switch never latched";
  // Where it closes, in board counts: switch_m less the start. Tolerance
  // one count: open loop, POS and the latch count the steps sent, which
  // lead the rotor (whose table position closes the switch) by its load
  // angle, under a step here; the pin changes at the plant step after the
  // crossing (1 us), and the synchronizer and the 4-clock filter add under
  // a microsecond: at locate_m_s (200 counts/s) 0.0004 counts in those 2 us.
  const int64_t closes = counts(x, h.switch_m - start);
  const int32_t latched = r.reg(kX, br::AX_IDX);
  EXPECT_LE(std::llabs(latched - closes), 1) << "latched " << latched << ", closes at " << closes;
  // The contact bounced (a clean switch changes once) and settled closed.
  EXPECT_GE(r.board.limit_edges(kX), 5u);
  EXPECT_TRUE(r.board.limit_pin(kX));
  EXPECT_TRUE(r.link.read(br::IO_STAT) >> (bb::IOS_HOME_LSB + kX) & 1);
  EXPECT_EQ(r.link.read(br::FAULT), 0u);

  // Backing off opens it again, bouncing as well; the latch keeps the first
  // closing (one latch per arming), and the home bit clears.
  const uint64_t edges = r.board.limit_edges(kX);
  ASSERT_TRUE(r.move({0, 0, 0}, h.seek_m_s));
  EXPECT_FALSE(r.board.limit_pin(kX));
  EXPECT_GE(r.board.limit_edges(kX), edges + 5);
  EXPECT_FALSE(r.link.read(br::IO_STAT) >> (bb::IOS_HOME_LSB + kX) & 1);
  EXPECT_EQ(r.reg(kX, br::AX_IDX), latched);
  std::printf("X from %.7f m: the switch at %.4f m closes at count %lld, latched %d; %llu pin edges\n", start,
              h.switch_m, static_cast<long long>(closes), latched,
              static_cast<unsigned long long>(r.board.limit_edges(kX)));
}

// Z lowered onto a tilted, bowed plate with the probe latching every axis
// and stopping the motion: the latched Z is the face under the tool.
TEST(VBoardIo, TheProbeLatchesTheWorkpiecesFace) {
  machine::MachineConfig m = stepper_router();
  m.workpiece = plate();
  const double x0 = 0.0123, y0 = 0.0217, z0 = -0.0035;
  Rig r(m, {x0, y0, z0}, 3);
  const double face_mm = machine::surface_z_mm(*m.workpiece, x0 * 1e3, y0 * 1e3);
  ASSERT_LT(face_mm, z0 * 1e3) << "the tool starts above the face";
  ASSERT_FALSE(r.board.probe_pin());
  r.arm();
  r.latch({bb::L_SRC_PROBE, bb::L_SRC_PROBE, bb::L_SRC_PROBE}, true);
  const machine::AxisConfig& z = m.axes[kZ];
  const int64_t target = counts(z, -0.003);  // 3 mm down: well into the plate
  constexpr double kProbeFeed = 0.002;       // 120 mm/min
  ASSERT_TRUE(r.move({0, 0, target}, kProbeFeed));

  for (int a = 0; a < 3; ++a) ASSERT_TRUE(r.latched(a)) << "axis " << a << " did not latch";
  // The face in board counts: surface_z_mm less the start. Within one
  // count, as the home switch (at 800 counts/s here, 0.002 counts in 2 us).
  const int64_t face = counts(z, face_mm * 1e-3 - z0);
  const int32_t latched = r.reg(kZ, br::AX_IDX);
  EXPECT_LE(std::llabs(latched - face), 1) << "latched " << latched << ", the face at " << face;
  EXPECT_EQ(r.reg(kX, br::AX_IDX), 0);
  EXPECT_EQ(r.reg(kY, br::AX_IDX), 0);
  // The latch stopped the interpolator at the face, far short of the target.
  const int32_t cmd = r.reg(kZ, br::AX_CMD);
  EXPECT_LE(std::llabs(cmd - face), 3) << "stopped at " << cmd;
  EXPECT_GT(cmd, target / 2) << "it went on towards " << target;
  EXPECT_NEAR(r.board.position_m(kZ) * 1e3, face_mm, 0.01);
  EXPECT_TRUE(r.board.probe_pin());
  EXPECT_TRUE(r.link.read(br::IO_STAT) >> bb::IOS_PROBE & 1);
  EXPECT_GE(r.board.probe_edges(), 3u) << "the touch bounced";
  std::printf("face at %.4f mm under X %.1f Y %.1f: %lld counts, latched %d, stopped at %d\n", face_mm,
              x0 * 1e3, y0 * 1e3, static_cast<long long>(face), latched, cmd);
}

// Counter states below `duty` in n consecutive clocks of the 1024-clock
// PWM period, whatever the phase: whole periods give duty each, the rest
// between none and all of its clocks.
struct Bounds {
  uint64_t lo, hi;
};
Bounds pwm_high_bounds(uint64_t n, uint64_t duty) {
  const uint64_t whole = n / 1024 * duty, rest = n % 1024;
  return {whole + (rest > 1024 - duty ? rest - (1024 - duty) : 0), whole + std::min(rest, duty)};
}

// The spindle on at duty 512 with flood, then the drives disarmed: both
// changes logged at their clock, the duty counted over the twin's skipped
// stretches as well, and everything off with the drives.
TEST(VBoardIo, TheSpindleAndCoolantAreRecordedAndStopWithTheDrives) {
  Rig r(stepper_router(), {0, 0, 0});
  r.arm();
  EXPECT_TRUE(r.board.spindle_log().empty());
  r.link.write(br::IO_CTRL, 1u << bb::IO_SPINDLE | 1u << bb::IO_SPINDLE_REV | 1u << bb::IO_FLOOD |
                                512u << bb::IO_DUTY_LSB);
  const uint64_t stepped0 = r.board.stepped_clocks(), cycles0 = r.board.cycles();
  r.link.poll(std::chrono::milliseconds(50));
  // With nothing else to do the twin skipped most clocks: the count of the
  // high ones came from the PWM counter, not the pin.
  EXPECT_LT(r.board.stepped_clocks() - stepped0, (r.board.cycles() - cycles0) / 2);
  EXPECT_EQ(r.board.spindle_state(), (VirtualBoard::SpindleState{true, true, true}));
  r.link.write(br::CTRL, 0);
  r.link.poll(std::chrono::milliseconds(1));

  const auto& log = r.board.spindle_log();
  ASSERT_EQ(log.size(), 2u);
  EXPECT_EQ(log[0].state, (VirtualBoard::SpindleState{true, true, true}));
  EXPECT_EQ(log[0].pwm_high, 0u) << "off before";
  EXPECT_EQ(log[1].state, (VirtualBoard::SpindleState{}));
  EXPECT_EQ(r.board.spindle_state(), (VirtualBoard::SpindleState{}));
  // The counter has 1024 states and the pin is high in the 512 below the
  // duty: 512 of every 1024 clocks, exactly (IO_CTRL's "of 1023" is the
  // code for always on; 512/1023 would be half a clock more per period).
  // The interval ends mid-period: its high clocks lie within the bounds
  // any phase allows, a few hundred clocks wide over 600 000.
  const uint64_t n = log[1].clock - log[0].clock;
  EXPECT_EQ(log[1].pwm_clocks, n);
  EXPECT_GT(n, 600'000u);
  const Bounds b = pwm_high_bounds(n, 512);
  EXPECT_GE(log[1].pwm_high, b.lo);
  EXPECT_LE(log[1].pwm_high, b.hi);
  EXPECT_NEAR(log[1].duty(), 512.0 / 1024, 512.0 / double(n));
  r.link.poll(std::chrono::milliseconds(5));
  EXPECT_EQ(r.board.spindle_high_clocks(), log[1].pwm_high) << "SP_PWM stays low, disarmed";
  std::printf("spindle on for %llu clocks: SP_PWM high %llu (%.6f), bounds %llu..%llu\n",
              static_cast<unsigned long long>(n), static_cast<unsigned long long>(log[1].pwm_high),
              log[1].duty(), static_cast<unsigned long long>(b.lo), static_cast<unsigned long long>(b.hi));
}

// One scenario on the twin and on the Verilated board: X through its home
// switch while Z touches the plate (both latching), the spindle on at an
// odd duty, reversed, then disarmed. Same log, latches, pin edges, clocks.
struct Outcome {
  std::vector<VirtualBoard::SpindleEvent> log;
  std::vector<int32_t> regs;
  uint64_t lim_edges = 0, probe_edges = 0, cycles = 0, stepped = 0;
};

Outcome scenario(sim::BoardEngine e) {
  machine::MachineConfig m = stepper_router();
  m.workpiece = plate();
  const double x0 = m.axes[kX].home->switch_m - 0.0001, y0 = 0.02;
  const double z0 = machine::surface_z_mm(*m.workpiece, x0 * 1e3, y0 * 1e3) * 1e-3 + 0.00004;
  Rig r(m, {x0, y0, z0}, 0, e);
  r.link.write(br::SAFETY, 1u << bb::S_ESTOP_EN);
  r.arm();
  r.latch({bb::L_SRC_HOME, bb::L_SRC_NONE, bb::L_SRC_PROBE}, false);
  r.link.write(br::IO_CTRL, 1u << bb::IO_SPINDLE | 1u << bb::IO_FLOOD | 300u << bb::IO_DUTY_LSB);
  EXPECT_TRUE(r.move({counts(m.axes[kX], 0.0002), 0, counts(m.axes[kZ], -0.00008)}, 0.01));
  r.link.write(br::IO_CTRL, 1u << bb::IO_SPINDLE | 1u << bb::IO_SPINDLE_REV | 700u << bb::IO_DUTY_LSB);
  r.link.poll(std::chrono::milliseconds(2));
  r.link.write(br::CTRL, 0);
  r.link.poll(std::chrono::milliseconds(1));
  Outcome o;
  o.log = r.board.spindle_log();
  for (int a : {kX, kZ}) {
    o.regs.push_back(r.reg(a, br::AX_IDX));
    o.regs.push_back(int32_t(r.latched(a)));
  }
  o.regs.push_back(int32_t(r.link.read(br::IO_STAT)));
  o.regs.push_back(int32_t(r.link.read(br::FAULT)));
  o.lim_edges = r.board.limit_edges(kX);
  o.probe_edges = r.board.probe_edges();
  o.cycles = r.board.cycles();
  o.stepped = r.board.stepped_clocks();
  return o;
}

TEST(VBoardIo, TwinAndRtlRecordTheSame) {
  const Outcome twin = scenario(sim::BoardEngine::Twin);
  const Outcome rtl = scenario(sim::BoardEngine::Rtl);
  std::printf("%.4f s of board time; twin stepped %llu of %llu clocks; %zu spindle events\n",
              double(twin.cycles) / 12e6, static_cast<unsigned long long>(twin.stepped),
              static_cast<unsigned long long>(twin.cycles), twin.log.size());
  // The scenario did what it says: both latched, the switch and the probe
  // bounced, the spindle went on, reversed and off.
  ASSERT_EQ(twin.regs.size(), 6u);
  EXPECT_EQ(twin.regs[1], 1) << "X latched";
  EXPECT_EQ(twin.regs[3], 1) << "Z latched";
  EXPECT_GE(twin.lim_edges, 3u);
  EXPECT_GE(twin.probe_edges, 3u);
  ASSERT_EQ(twin.log.size(), 3u);
  EXPECT_EQ(twin.log[2].state, (VirtualBoard::SpindleState{}));
  EXPECT_LT(twin.stepped, twin.cycles);
  EXPECT_EQ(rtl.stepped, rtl.cycles);

  EXPECT_EQ(twin.cycles, rtl.cycles);
  EXPECT_EQ(twin.regs, rtl.regs);
  EXPECT_EQ(twin.lim_edges, rtl.lim_edges);
  EXPECT_EQ(twin.probe_edges, rtl.probe_edges);
  ASSERT_EQ(twin.log.size(), rtl.log.size());
  for (size_t i = 0; i < twin.log.size(); ++i) {
    EXPECT_EQ(twin.log[i], rtl.log[i])
        << "event " << i << ": clock " << twin.log[i].clock << " / " << rtl.log[i].clock << ", SP_PWM high "
        << twin.log[i].pwm_high << " / " << rtl.log[i].pwm_high;
  }
}

// A table that starts on its switch shows it closed from power-up, without
// bounce (nothing crossed it), and the board still goes dormant once the
// link has been quiet that long; start_at() is for before the first run.
TEST(VBoardIo, ATableStartedOnItsSwitchShowsItClosedWithoutBounce) {
  const machine::MachineConfig m = stepper_router();
  const double sw = m.axes[kX].home->switch_m;
  sim::VirtualBoard b(m);
  b.start_at(kX, sw);
  EXPECT_TRUE(b.limit_pin(kX));
  std::vector<uint8_t> out;
  b.run(sim::kMaxWatchdogClocks + 24, out);
  EXPECT_TRUE(b.dormant());
  EXPECT_EQ(b.limit_edges(kX), 0u);
  EXPECT_THROW(b.start_at(kX, 0), std::logic_error) << "only before the first run";
}

}  // namespace
}  // namespace mc::test
