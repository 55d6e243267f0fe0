// Machine cycles on the virtual board (issue 19): homing from random start
// positions sets the same machine zero every time, and probing a known
// surface reports its height, both measured against the plant: the table
// positions the virtual board was started at and the workpiece face the
// probe touches (host/machine/cycles.hpp).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/cycles.hpp"
#include "host/machine/job.hpp"
#include "host/machine/probe_grid.hpp"
#include "host/machine/workpiece.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

machine::MachineConfig load(const char* name) {
  return machine::load_machine(std::string(MC_SOURCE_DIR) + "/configs/" + name);
}

// A board in process whose tables start at start_m (the plant's frame).
struct Rig {
  Rig(const machine::MachineConfig& m, const std::array<double, 3>& start_m, uint32_t seed)
      : cfg(m), board(m, seed), stream(board), link(stream) {
    for (int a = 0; a < int(m.axes.size()); ++a) board.start_at(a, start_m[size_t(a)]);
    link.connect();
  }
  machine::MachineConfig cfg;
  sim::VirtualBoard board;
  sim::BoardStream stream;
  host::BoardLink link;
};

double cpm(const machine::MachineConfig& m, int a) {
  return machine::counts_per_m(m.axes[size_t(a)]);
}

// The board count at the plant's 0: what machine zero must be, since the
// switches sit at switch_m in the plant's frame. Start s: POS counts from
// s, so table 0 is at -s; POS is floor(position), a count's quantization.
double zero_count(const machine::MachineConfig& m, int a, double start_m) {
  return -start_m * cpm(m, a);
}

void home_from_random_starts(const char* config, int cycles, uint32_t seed) {
  machine::MachineConfig m = load(config);
  // The seek only finds the switch; the locate's latch is the one that
  // counts. A faster seek keeps board time short without touching it, on a
  // servo; a stepper keeps its configured seek, the speed it may start and
  // stop at without a ramp (faster, it loses steps, and the latch, which
  // counts steps sent, misses where the table is).
  for (machine::AxisConfig& a : m.axes)
    if (!a.stepper) a.home->seek_m_s = std::min(0.15, a.max_speed_m_s);
  std::mt19937 rng(seed);
  std::array<double, 3> worst{};
  for (int n = 0; n < cycles; ++n) {
    std::array<double, 3> start{};
    for (size_t a = 0; a < m.axes.size(); ++a) {
      const machine::AxisConfig& ax = m.axes[a];
      // Anywhere in the travel, off the switch by more than the contact's
      // bounce and the filter (the cycle's own case for a closed switch is
      // below).
      const double lo = ax.home->direction > 0 ? ax.travel_min_m : ax.home->switch_m + 0.001;
      const double hi = ax.home->direction > 0 ? ax.home->switch_m - 0.001 : ax.travel_max_m;
      start[a] = std::uniform_real_distribution<double>(lo, hi)(rng);
    }
    Rig r(m, start, uint32_t(n + 1));
    const host::Vec3 origin = machine::home_axes(r.link, m, 7);
    const host::MachineOrigin read = host::read_origin(r.link);
    EXPECT_EQ(read.homed, 7u);
    EXPECT_EQ(read.counts, origin);
    for (size_t a = 0; a < m.axes.size(); ++a) {
      const double want = zero_count(m, int(a), start[a]);
      // Within a count of the count nearest the plant's zero: the switch
      // closes between two counts, the latch takes the count the axis is on.
      const double e = double(origin[a]) - want;
      worst[a] = std::max(worst[a], std::fabs(e));
      EXPECT_LE(std::llabs(origin[a] - std::llround(want)), 1)
          << config << " cycle " << n << " axis " << a << ": origin " << origin[a] << ", the plant's zero at "
          << want;
      // Parked pull_off away from the switch, in machine coordinates.
      const machine::HomeConfig& h = *m.axes[a].home;
      const int64_t cmd = int32_t(r.link.read(br::axis(int(a), br::AX_CMD)));
      EXPECT_NEAR(double(cmd - origin[a]) / cpm(m, int(a)), h.switch_m - h.direction * h.pull_off_m,
                  1.5 / cpm(m, int(a)));
    }
    // The limits are back on, and the latches off.
    EXPECT_EQ(r.link.read(br::SAFETY), bb::SAFETY_DEFAULT);
    EXPECT_EQ(r.link.read(br::FAULT), 0u);
  }
  std::printf("%s: %d homing cycles, worst machine zero against the plant's: x %.3f, y %.3f, z %.3f counts\n",
              config, cycles, worst[0], worst[1], worst[2]);
}

TEST(Homing, ServoMachineZeroIsRepeatableWithinACount) {
  home_from_random_starts("default.toml", 20, 19);
}

TEST(Homing, StepperMachineZeroIsRepeatableWithinACount) {
  home_from_random_starts("stepper_router.toml", 2, 7);
}

TEST(Homing, AnAxisOnItsSwitchBacksOffFirst) {
  machine::MachineConfig m = load("default.toml");
  const machine::HomeConfig& h = *m.axes[2].home;
  Rig r(m, {0, 0, h.switch_m + 0.0005 * h.direction}, 3);
  EXPECT_TRUE(r.link.read(br::IO_STAT) >> (bb::IOS_HOME_LSB + 2) & 1) << "Z starts on its switch";
  const host::Vec3 origin = machine::home_axes(r.link, m, 4);
  EXPECT_LE(std::fabs(double(origin[2]) - zero_count(m, 2, h.switch_m + 0.0005 * h.direction)), 1.0);
  EXPECT_EQ(host::read_origin(r.link).homed, 4u) << "Z alone";
}

TEST(Homing, NoSwitchWithinTheSearchIsAlarmNine) {
  machine::MachineConfig m = load("default.toml");
  // The switch beyond 1.5 x the travel: the seek ends without a latch.
  m.axes[2].home->switch_m = 5.0;
  Rig r(m, {0, 0, 0}, 4);
  ASSERT_EQ(r.link.read(br::SAFETY), bb::SAFETY_DEFAULT);
  try {
    machine::home_axes(r.link, m, 4);
    FAIL() << "homed without a switch";
  } catch (const machine::CycleError& e) {
    EXPECT_EQ(e.grbl_alarm(), 9) << e.what();
  }
  EXPECT_EQ(r.link.read(br::SAFETY), bb::SAFETY_DEFAULT) << "the limits are restored after a failed cycle";
  EXPECT_EQ(host::read_origin(r.link).homed, 0u);
}

TEST(Homing, AnAxisWithoutASwitchIsRefusedBeforeAnythingMoves) {
  machine::MachineConfig m = load("default.toml");
  m.axes[1].home.reset();
  EXPECT_THROW(machine::homing_plan(m, 7), host::InputError);
}

// A plain move of the command, waited for (the axes caught up).
void move_to(host::BoardLink& l, const host::Vec3& from, const host::Vec3& to, double feed_counts_s) {
  machine::LatchedMove mv(l, {from, to, feed_counts_s, machine::LatchedMove::Source::none, 0, false});
  while (!mv.poll()) machine::wait_on_link(l);
}

TEST(Probing, TwentyFivePointsOnAKnownSurfaceWithinACount) {
  const machine::MachineConfig m = load("default.toml");
  ASSERT_TRUE(m.workpiece);
  const machine::WorkpieceConfig& w = *m.workpiece;
  Rig r(m, {0, 0, 0.002}, 21);  // the tool 2 mm above the plate's corner
  const machine::JobBoard jb = machine::ready_board(r.link, m, {});
  host::Vec3 at = jb.at;
  const double cx = cpm(m, 0) * 1e-3, cz = cpm(m, 2) * 1e-3;  // counts per mm
  const double clear_mm = 1.0;  // board mm: 3 mm above the plate's corner, 2.5 mm above its highest point
  int worst = 0;
  for (int iy = 0; iy < 5; ++iy)
    for (int ix = 0; ix < 5; ++ix) {
      const double x = 10 + ix * 45.0, y = 10 + iy * 32.5;  // mm, over the plate
      host::Vec3 above{std::llround(x * cx), std::llround(y * cx), std::llround(clear_mm * cz)};
      move_to(r.link, at, above, 50 * cx);
      host::Vec3 down = above;
      down[2] = std::llround(-4.0 * cz);
      machine::ProbeCycle p(r.link, above, down, 5.0 * cz, true, 7);  // 300 mm/min
      while (!p.poll()) machine::wait_on_link(r.link);
      ASSERT_TRUE(p.contact()) << "no contact at " << x << ", " << y;
      at = p.end();
      // The face under where the table truly is (X and Y hold within a
      // count or two of their command while Z probes).
      const double face_mm =
          machine::surface_z_mm(w, r.board.position_m(0) * 1e3, r.board.position_m(1) * 1e3);
      // The count the encoder shows there: Z's counts start 2 mm up.
      const int64_t face = int64_t(std::floor((face_mm - 2.0) * cz));
      const int64_t got = p.position()[2];
      worst = std::max<int>(worst, int(std::llabs(got - face)));
      EXPECT_LE(std::llabs(got - face), 1)
          << "at " << x << ", " << y << ": latched " << got << ", face " << face_mm << " mm = count " << face;
      // Every axis latched in the same clock: X and Y where they stood.
      EXPECT_LE(std::llabs(p.position()[0] - above[0]), 3);
      EXPECT_LE(std::llabs(p.position()[1] - above[1]), 3);
    }
  std::printf("25 probe points: worst |latched Z - the face's count| = %d counts (%.2f um each)\n", worst,
              1e3 / cz);
}

TEST(Probing, AProbeAlreadyTouchingIsAlarmFour) {
  const machine::MachineConfig m = load("default.toml");
  Rig r(m, {0.05, 0.05, -0.01}, 22);  // the tool 10 mm into the plate: the probe is closed
  const machine::JobBoard jb = machine::ready_board(r.link, m, {});
  host::Vec3 to = jb.at;
  to[2] -= 100;
  try {
    machine::ProbeCycle p(r.link, jb.at, to, 100, true, 7);
    FAIL() << "probed while touching";
  } catch (const machine::CycleError& e) {
    EXPECT_EQ(e.grbl_alarm(), 4) << e.what();
  }
  EXPECT_EQ(r.link.read(br::LATCH), 0u) << "LATCH restored";
  // Away from contact (G38.4) is what it may do: it opens going up.
  host::Vec3 up = jb.at;
  up[2] += std::llround(20.0 * cpm(m, 2) * 1e-3);
  machine::ProbeCycle p(r.link, jb.at, up, 2.0 * cpm(m, 2) * 1e-3, false, 7);
  while (!p.poll()) machine::wait_on_link(r.link);
  EXPECT_TRUE(p.contact());
  const double face = machine::surface_z_mm(*m.workpiece, 50, 50) * cpm(m, 2) * 1e-3;
  EXPECT_LE(std::fabs(double(p.position()[2]) - (face - (-0.01 * cpm(m, 2)))), 2.0)
      << "opened at the face (board counts from the start 10 mm below it)";
}

// level probe's grid: every height of the map is the face's under the
// point, relative to the first point's, within the two contacts' counts;
// the map is the one a perfect probe takes (sample_height_map) as closely.
TEST(Probing, AGridMapsTheFaceRelativeToItsFirstPoint) {
  const machine::MachineConfig m = load("default.toml");
  const machine::WorkpieceConfig& w = *m.workpiece;
  Rig r(m, {0, 0, 0.003}, 23);  // 3 mm above the plate's corner: machine X, Y are the plant's
  machine::ProbeGridOptions o;
  o.nx = 3;
  o.ny = 2;
  o.x0 = 20;
  o.y0 = 20;
  o.x1 = 180;
  o.y1 = 130;
  int calls = 0;
  const machine::ProbedGrid g = machine::probe_grid(r.link, m, o, {}, [&](int done, int total) {
    EXPECT_EQ(done, calls++);
    EXPECT_EQ(total, 6);
  });
  EXPECT_EQ(calls, 7);  // ready, then each point
  ASSERT_EQ(g.map.nx, 3);
  ASSERT_EQ(g.map.ny, 2);
  EXPECT_DOUBLE_EQ(g.map.x1(), 180);
  EXPECT_DOUBLE_EQ(g.map.y1(), 130);
  const double count_mm = 1e3 / cpm(m, 2);
  // Machine Z counts from where Z started, 3 mm above the plant's 0.
  const double z0 = machine::surface_z_mm(w, 20, 20);
  EXPECT_NEAR(g.z0_mm, z0 - 3, count_mm + 1e-9);
  double worst = 0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i) {
      const double want = machine::surface_z_mm(w, 20 + 80 * i, 20 + 110 * j) - z0;
      worst = std::max(worst, std::fabs(g.map.at(i, j) - want));
      EXPECT_NEAR(g.map.at(i, j), want, 2 * count_mm + 1e-9) << "point " << i << ", " << j;
    }
  EXPECT_EQ(g.map.at(0, 0), 0);
  std::printf("6-point grid: worst |map - face| = %.2f um (a Z count is %.2f um)\n", worst * 1e3,
              count_mm * 1e3);
  // The tool ends clear of the work: the probe open.
  EXPECT_FALSE(machine::probe_closed(r.link));
  // A grid too large for the travel is refused before anything moves.
  o.x1 = 400;
  const int32_t x_before = int32_t(r.link.read(br::axis(0, br::AX_CMD)));
  EXPECT_THROW(machine::probe_grid(r.link, m, o), host::InputError);
  EXPECT_EQ(int32_t(r.link.read(br::axis(0, br::AX_CMD))), x_before);
}

}  // namespace
}  // namespace mc::test
