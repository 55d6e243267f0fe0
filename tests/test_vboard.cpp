// The virtual board on its two engines: the board twin, which skips the
// clocks in which only counters move, against the Verilated board clocked
// one by one. The same host session (gains, arming, a move, telemetry,
// reads) on both must give the same TX bytes at the same clocks and the
// same plant positions, step for step: what the twin engine skips changes
// nothing a host or a plant can see.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "host/control/board_gains.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/motion/board_run.hpp"
#include "host/motion/interp_plan.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;

struct Session {
  std::vector<std::pair<uint64_t, uint8_t>> tx;
  std::vector<double> pos;
  std::vector<uint32_t> reads;
  std::vector<sim::VirtualBoard::EncoderEdge> edges;  // in clock order, then by axis
  std::string stopped;                                // why the move stopped early (empty: it did not)
  uint64_t cycles = 0, stepped = 0, held = 0, lim_edges = 0;
  double wall_s = 0;
};

// Gains on X and Y, armed, a diagonal move at the machine's feed with
// telemetry streaming, then the positions and counters read back. The
// table's Z at z_m: 0 on the workpiece's face (the probe touching), or
// clear of it (the twin then runs the plants by held runs). A plant step of
// clocks_per_step clocks (0: the machine's).
// The move: from (x0, 0) by (dx, dy) at feed (m/s), on a PID sample period
// of ts.
// quiet: the whole move queued at once, then no host traffic while it runs
// (else the host streams it and polls).
struct Move {
  double x0 = 0, dx = 0.4e-3, dy = -0.3e-3, feed = 0.025, ts = 100e-6;
  bool quiet = false;
};
Session session(sim::BoardEngine e, double z_m = 0, uint32_t clocks_per_step = 0, const Move& mv = {}) {
  machine::MachineConfig m = machine::default_machine();
  if (clocks_per_step != 0) m.plant_dt_s = clocks_per_step / m.clock_hz;
  sim::VirtualBoard board(m, 0, e);
  board.start_at(0, mv.x0);
  board.start_at(2, z_m);
  sim::BoardStream s(board, true);
  Session r;
  board.log_encoder_edges(&r.edges);
  host::BoardLink link(s);
  const auto t0 = std::chrono::steady_clock::now();
  link.connect();
  link.write(br::WDOG, (1u << 24) - 1);
  const host::Note quiet = [](const std::string&) {};
  for (int a = 0; a < 2; ++a) {
    const machine::PidConfig& c = m.axes[size_t(a)].pid;
    host::PidGains g{};
    g.kp = c.kp;
    g.ki = c.ki;
    g.kd = c.kd;
    g.tf = c.tf_s;
    g.ts = mv.ts;
    host::CoreLimits lim;
    lim.out_limit = uint32_t(c.out_limit);
    host::apply_gains(link, a, g, lim, quiet);
  }
  host::enable_axes(link, {0, 1}, quiet);
  link.write(br::TLM, 0x3u << 16 | 20);  // X and Y every 20th sample
  const double cpm = machine::counts_per_m(m.axes[0]);
  const host::Vec3 to{std::llround(mv.dx * cpm), std::llround(mv.dy * cpm), 0};
  const auto plan = host::plan_move({0, 0, 0}, to, mv.feed * cpm, m.clock_hz);
  if (mv.quiet) {
    std::vector<seg::Words> words;
    words.reserve(plan.size());
    for (const auto& p : plan) words.push_back(seg::pack(p.seg));
    for (size_t i = 0; i < words.size(); i += 6)
      EXPECT_TRUE(
          link.segments({words.begin() + long(i), words.begin() + long(std::min(words.size(), i + 6))}));
    link.poll(std::chrono::milliseconds(30));
  } else {
    try {
      host::run_segments(link, plan);
    } catch (const std::exception& ex) {  // a fault stopped it: a switch reached
      r.stopped = ex.what();
    }
  }
  link.write(br::TLM, 0);
  link.poll(std::chrono::milliseconds(5));  // the move settles
  for (uint16_t reg : {br::STATUS, br::FAULT, br::IP_SEGS, br::LINK_CRC, br::LINK_CMD})
    r.reads.push_back(link.read(reg));
  for (int a = 0; a < 2; ++a) r.reads.push_back(link.read(uint16_t(br::AXIS_BASE + a * br::AXIS_STRIDE)));
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.tx = std::move(s.tx);
  r.pos = std::move(s.pos);
  r.cycles = board.cycles();
  r.stepped = board.stepped_clocks();
  r.held = board.held_steps();
  r.lim_edges = board.limit_edges(0);
  board.log_encoder_edges(nullptr);
  std::stable_sort(r.edges.begin(), r.edges.end(), [](const auto& x, const auto& y) {
    return x.clock != y.clock ? x.clock < y.clock : x.axis < y.axis;
  });
  return r;
}

void expect_same(const Session& twin, const Session& rtl) {
  EXPECT_EQ(twin.cycles, rtl.cycles);
  ASSERT_EQ(twin.tx.size(), rtl.tx.size());
  for (size_t i = 0; i < twin.tx.size(); ++i) ASSERT_EQ(twin.tx[i], rtl.tx[i]) << "TX byte " << i;
  ASSERT_EQ(twin.pos.size(), rtl.pos.size());
  for (size_t i = 0; i < twin.pos.size(); ++i) ASSERT_EQ(twin.pos[i], rtl.pos[i]) << "position " << i;
  EXPECT_EQ(twin.reads, rtl.reads);
  EXPECT_EQ(twin.lim_edges, rtl.lim_edges);
  EXPECT_EQ(twin.stopped, rtl.stopped);
  // The encoder pins changed at the same clocks (the PID reads a count only
  // at its tick: an edge shown late inside a stretch would show nowhere else).
  ASSERT_EQ(twin.edges.size(), rtl.edges.size());
  for (size_t i = 0; i < twin.edges.size(); ++i)
    ASSERT_EQ(twin.edges[i], rtl.edges[i]) << "encoder edge " << i << " at clock " << rtl.edges[i].clock;
}

TEST(VBoard, TwinAndRtlGiveIdenticalOutputs) {
  const Session twin = session(sim::BoardEngine::Twin);
  const Session rtl = session(sim::BoardEngine::Rtl);
  for (const Session* s : {&twin, &rtl})
    std::printf(
        "%s: %.4f s of board time in %.3f s (%.2fx real time), %llu of %llu clocks stepped, %zu TX bytes\n",
        s == &twin ? "twin" : "rtl", double(s->cycles) / 12e6, s->wall_s,
        double(s->cycles) / 12e6 / s->wall_s, static_cast<unsigned long long>(s->stepped),
        static_cast<unsigned long long>(s->cycles), s->tx.size());
  // The session did what it says: telemetry flowed, the axes moved (the
  // encoder counts read back, X then Y, near the target), and the twin
  // skipped clocks.
  EXPECT_GT(twin.tx.size(), 2000u);
  ASSERT_EQ(twin.reads.size(), 7u);
  const double cpm = machine::counts_per_m(machine::default_machine().axes[0]);
  EXPECT_NEAR(double(int32_t(twin.reads[5])), 0.4e-3 * cpm, 0.05e-3 * cpm);
  EXPECT_NEAR(double(int32_t(twin.reads[6])), -0.3e-3 * cpm, 0.05e-3 * cpm);
  EXPECT_LT(twin.stepped, twin.cycles * 3 / 4) << "the twin engine skipped little";
  EXPECT_EQ(rtl.stepped, rtl.cycles);
  expect_same(twin, rtl);
}

// The same 2 mm above the face: no switch near, the twin runs the plants
// by held runs of equal drive where it skips the board (held), the RTL
// steps them one by one; the positions (recorded at every TX byte) and
// bytes are the same.
TEST(VBoard, HeldPlantRunsGiveTheStepsTheRtlTakes) {
  const Session twin = session(sim::BoardEngine::Twin, 0.002);
  const Session rtl = session(sim::BoardEngine::Rtl, 0.002);
  EXPECT_GT(twin.held, twin.cycles / 12 / 5) << "the plants ran by holds in under a fifth of the steps";
  EXPECT_EQ(rtl.held, 0u);
  EXPECT_GT(twin.edges.size(), 250u) << "the tables hardly moved";
  expect_same(twin, rtl);
}

// X across its home switch, fast, on a 2 ms sample period: a stretch of the
// board runs a sample long, in which X moves 40 counts, and the twin's
// jumps take encoder edges inside; a jump must still end before the table
// could reach the switch, which then trips in the RTL's step.
TEST(VBoard, EdgesInsideJumpsStopShortOfASwitch) {
  const machine::MachineConfig m = machine::default_machine();
  Move mv;
  mv.x0 = m.axes[0].home->switch_m - 0.3e-3;
  mv.dx = 0.6e-3;
  mv.dy = 0;
  mv.feed = 0.05;
  mv.ts = 2e-3;
  mv.quiet = true;
  const Session twin = session(sim::BoardEngine::Twin, 0.002, 0, mv);
  const Session rtl = session(sim::BoardEngine::Rtl, 0.002, 0, mv);
  EXPECT_GE(twin.lim_edges, 1u) << "X never reached its switch";
  EXPECT_NE(twin.reads[1] >> board::bits::F_LIMIT_LSB & 1, 0u) << "no limit fault on X";
  EXPECT_GT(twin.held, twin.cycles / 12 / 5) << "the plants ran by holds in under a fifth of the steps";
  expect_same(twin, rtl);
}

// A host that opens the port at once is answered at once: its first frame
// is not lost to the board's power-on reset (which would cost its first
// timeout, 200 ms of board time, on both engines).
TEST(VBoard, AHostConnectsWithoutRetrying) {
  for (const sim::BoardEngine e : {sim::BoardEngine::Twin, sim::BoardEngine::Rtl}) {
    sim::VirtualBoard board(machine::default_machine(), 0, e);
    sim::BoardStream s(board);
    host::BoardLink link(s);
    link.connect();
    std::printf("%s: connected after %llu clocks\n", sim::board_engine_name(e),
                static_cast<unsigned long long>(board.cycles()));
    EXPECT_EQ(link.counters().retransmits, 0u) << sim::board_engine_name(e);
    EXPECT_LT(board.cycles(), 12'000u) << sim::board_engine_name(e) << ": over a millisecond";
  }
}

// Plant steps of 4 clocks, shorter than the half bit by which the board's
// stretch may outlast the byte its receiver takes: each TX byte still comes
// out in the step the RTL's does.
TEST(VBoard, ShortPlantStepsGiveTheBytesInTheRtlsSteps) {
  const Session twin = session(sim::BoardEngine::Twin, 0.002, 4);
  const Session rtl = session(sim::BoardEngine::Rtl, 0.002, 4);
  EXPECT_GT(twin.tx.size(), 2000u);
  expect_same(twin, rtl);
}

}  // namespace
}  // namespace mc::test
