// The path planner against analytic profiles and over random programs:
//  - the pieces form one continuous path that ends exactly at the program's
//    end, every commanded point within a count of the programmed path;
//  - no piece runs faster than its move allows, and the command's windowed
//    acceleration stays within every axis's limit;
//  - a rest-to-rest line takes the trapezoid's time; look-ahead spans the
//    whole program (many short collinear moves run as fast as one long one);
//  - a 90-degree corner runs at Grbl's junction-deviation speed;
//  - a stop from mid-move decelerates at the limit and ends on the path;
//  - what the machine cannot do is refused, naming the line.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "host/base/errors.hpp"
#include "host/gcode/interpreter.hpp"
#include "host/machine/job.hpp"
#include "host/machine/machine_config.hpp"
#include "host/motion/planner.hpp"

namespace {

using mc::host::Move;
using mc::host::Piece;
using mc::host::PlannerConfig;
using mc::host::Vec3d;

PlannerConfig config() {
  PlannerConfig c;
  for (size_t k = 0; k < 3; ++k) {
    c.axes[k].present = true;
    c.axes[k].counts_per_mm = 400;
    c.axes[k].max_rate_mm_s = k == 2 ? 250 : 500;
    c.axes[k].max_accel_mm_s2 = k == 2 ? 1000 : 2000;
    c.axes[k].min_mm = -300;
    c.axes[k].max_mm = 300;
  }
  return c;
}

struct Planned {
  std::vector<Move> moves;
  std::vector<Piece> pieces;
};

Planned plan(const std::string& program, const PlannerConfig& c = config(), Vec3d start = {}) {
  mc::gcode::Options o;
  o.start = start;
  const auto r = mc::gcode::interpret_program(program, "t.nc", o);
  EXPECT_TRUE(r.ok()) << (r.errors.empty() ? "" : r.errors[0].format());
  Planned p;
  p.moves = mc::host::to_moves(r.calls, start, c);
  mc::host::plan_speeds(p.moves, c);
  p.pieces = mc::host::chop(p.moves, c);
  return p;
}

// Distance to the path near move i (a piece's own move and its neighbours:
// a rounded junction point may sit on either side).
double path_distance(const std::vector<Move>& moves, size_t i, const Vec3d& p) {
  double d = 1e300;
  for (size_t k = i > 0 ? i - 1 : 0; k < std::min(moves.size(), i + 2); ++k)
    if (moves[k].is_motion()) d = std::min(d, mc::host::distance_to(moves[k], p));
  return d;
}

// Continuity, end point, every visited count near the path, speeds.
void check_pieces(const Planned& p, const PlannerConfig& c, const Vec3d& end) {
  ASSERT_FALSE(p.pieces.empty());
  mc::host::Vec3 at = p.pieces.front().seg.start;
  double t = 0;
  for (const Piece& x : p.pieces) {
    if (x.action) continue;
    ASSERT_EQ(x.seg.start, at) << "piece of line " << p.moves[size_t(x.move)].line
                               << " starts off the last end";
    at = x.seg.end;
    t += x.seg.duration;
    EXPECT_NEAR(x.t_end, t, 1e-9 * (1 + t));
    const Move& m = p.moves[size_t(x.move)];
    if (!m.is_motion()) continue;
    // Speed: the piece's path speed within the move's nominal speed.
    const double len_mm = x.seg.length / c.axes[0].counts_per_mm;
    // (Each end is rounded to a count: the piece may be up to two counts
    // longer than the path it stands for.)
    const double slack = 2 / c.axes[0].counts_per_mm / x.seg.duration;
    EXPECT_LE(len_mm / x.seg.duration, m.v_nominal * 1.001 + slack) << "line " << m.line;
    // Every count the core visits lies within two counts of the programmed
    // path: the rounding of the ends (up to 0.87 count in 3D) plus the
    // walk's own steps beside its chord.
    mc::host::walk(x.seg, [&](const mc::host::Vec3& q) {
      const double d = path_distance(p.moves, size_t(x.move), mc::host::to_mm(q, c));
      ASSERT_LE(d, 2.0 / c.axes[0].counts_per_mm) << "line " << m.line;
    });
  }
  EXPECT_EQ(at, mc::host::to_counts(end, c));
}

void check_accel(const Planned& p, const PlannerConfig& c) {
  const auto a = mc::host::peak_accel(p.pieces, c);
  for (size_t k = 0; k < 3; ++k)
    EXPECT_LE(a[k], 1.01 * c.axes[k].max_accel_mm_s2) << "axis "
                                                      << "XYZ"[k];
}

TEST(Planner, RestToRestLineTakesTheTrapezoidsTime) {
  const PlannerConfig c = config();
  // 100 mm at 6000 mm/min = 100 mm/s, a = 2000: ramps of 50 ms and 2.5 mm each.
  const Planned p = plan("G1 X100 F6000\n", c);
  check_pieces(p, c, {100, 0, 0});
  const double v = 100, a = 2000, l = 100;
  EXPECT_NEAR(p.pieces.back().t_end, l / v + v / (0.735 * a), 1e-6);  // ramps at 73.5 % of the limit
  const auto peak = mc::host::peak_accel(p.pieces, c);
  EXPECT_NEAR(peak[0], 0.735 * a, 0.01 * a);  // the ramp uses the limit less its margin
  EXPECT_LT(peak[1], 1e-9);
}

TEST(Planner, ShortLineIsATriangle) {
  const PlannerConfig c = config();
  const Planned p = plan("G1 X1 F6000\n", c);  // too short to reach 100 mm/s
  const double a = 2000, l = 1;
  EXPECT_NEAR(p.pieces.back().t_end, 2 * std::sqrt(l / (0.735 * a)), 1e-6);
}

TEST(Planner, LookAheadSpansTheWholeProgram) {
  const PlannerConfig c = config();
  std::ostringstream many;
  many << "G1 F6000\n";
  for (int i = 1; i <= 2000; ++i) many << "X" << i * 0.05 << "\n";  // 2000 moves of 0.05 mm
  const Planned a = plan(many.str(), c);
  const Planned b = plan("G1 X100 F6000\n", c);
  // Grbl's 16-block look-ahead would cap the speed at sqrt(2 a 16 * 0.05) = 56 mm/s.
  EXPECT_NEAR(a.pieces.back().t_end, b.pieces.back().t_end, 0.005 * b.pieces.back().t_end);
  check_accel(a, c);
}

TEST(Planner, RightAngleCornerRunsAtTheJunctionDeviationSpeed) {
  PlannerConfig c = config();
  c.accel_window_s = 1;  // the velocity-step cap far away: the deviation decides
  const Planned p = plan("G1 X50 F12000\nY50\n", c);
  ASSERT_EQ(p.moves.size(), 2u);
  // Grbl: v^2 = a d sin(t/2) / (1 - sin(t/2)); t = 90 deg, the junction's
  // direction (1,1)/sqrt2 allows a = 2000 * sqrt2.
  const double s = std::sqrt(0.5), a = 2000 * std::sqrt(2.0), d = c.junction_deviation_mm;
  EXPECT_NEAR(p.moves[1].v_entry, std::sqrt(a * d * s / (1 - s)), 1e-9);
  // G64 P widens it; G61 stops.
  EXPECT_NEAR(plan("G64 P0.1\nG1 X50 F12000\nY50\n", c).moves[1].v_entry, std::sqrt(a * 0.1 * s / (1 - s)),
              1e-9);
  EXPECT_EQ(plan("G61\nG1 X50 F12000\nY50\n", c).moves[1].v_entry, 0.0);
}

TEST(Planner, ArcsRunWholeOnTheCoreAndEndOnTheirPoint) {
  const PlannerConfig c = config();
  const Planned p = plan("G0 X10\nG2 X10 Y0 I-10 J0 F3000\nG3 X30 I10\nG18 G2 X40 Z0 I5 K0\n", c);
  int arcs = 0;
  for (const Piece& x : p.pieces) arcs += x.seg.seg.type == mc::seg::T_ARC;
  EXPECT_GT(arcs, 8);  // the full circle alone is at least four quarter turns
  check_pieces(p, c, {40, 0, 0});
  check_accel(p, c);
  // Centripetal: a 10 mm circle runs at most at sqrt(0.866 a R) = 131 mm/s.
  EXPECT_LE(p.moves[1].v_nominal, std::sqrt(0.8660254 * 0.735 * 2000 * 10) + 1e-9);
}

TEST(Planner, HelixBecomesChordsWithinTheArcTolerance) {
  const PlannerConfig c = config();
  const Planned p = plan("G0 X5\nG3 X5 Y0 Z-2 I-5 J0 P2 F1200\n", c);
  for (const Move& m : p.moves) EXPECT_EQ(m.kind, Move::Kind::line);
  EXPECT_GT(p.moves.size(), 20u);
  // Chord ends on the helix.
  for (const Move& m : p.moves) {
    if (m.rapid) continue;
    EXPECT_NEAR(std::hypot(m.end[0], m.end[1]), 5, 1e-9);
  }
  check_pieces(p, c, {5, 0, -2});
}

TEST(Planner, RandomProgramsStayOnThePathAndWithinTheLimits) {
  const PlannerConfig c = config();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-40, 40), z(-5, 1), f(300, 12000);
  for (int prog = 0; prog < 12; ++prog) {
    std::ostringstream g;
    g.precision(4);
    g << std::fixed;
    double x = 0, y = 0, zz = 0;
    for (int i = 0; i < 60; ++i) {
      const int kind = int(rng() % 5);
      if (kind == 0) {
        x = xy(rng), y = xy(rng), zz = z(rng);
        g << "G0 X" << x << " Y" << y << " Z" << zz << "\n";
      } else if (kind <= 2) {
        x = xy(rng), y = xy(rng);
        g << "G1 X" << x << " Y" << y << " F" << f(rng) << "\n";
      } else {
        // An arc about a centre 2..20 mm away, to a point on its circle.
        const double r = 2 + std::fabs(xy(rng)) / 2.2,
                     a0 = std::uniform_real_distribution<double>(0, 6.28)(rng);
        const double cx = x - r * std::cos(a0), cy = y - r * std::sin(a0);
        const double a1 = std::uniform_real_distribution<double>(0, 6.28)(rng);
        const double ex = cx + r * std::cos(a1), ey = cy + r * std::sin(a1);
        if (std::fabs(ex) > 290 || std::fabs(ey) > 290) continue;
        g << (kind == 3 ? "G2" : "G3") << " X" << ex << " Y" << ey << " I" << cx - x << " J" << cy - y << " F"
          << f(rng) << "\n";
        x = ex, y = ey;
      }
    }
    SCOPED_TRACE(g.str());
    const auto r = mc::gcode::interpret_program(g.str(), "r.nc");
    ASSERT_TRUE(r.ok());
    const Vec3d end{x, y, zz};  // the last point programmed
    const Planned p = plan(g.str(), c);
    check_pieces(p, c, end);
    check_accel(p, c);
  }
}

TEST(Planner, StopDeceleratesAtTheLimitAlongThePath) {
  const PlannerConfig c = config();
  const Planned p = plan("G1 X100 F6000\nY100\n", c);
  // A piece in the middle of the first move's cruise.
  size_t k = 0;
  while (p.pieces[k].seg.end[0] < int64_t(50) * 400) ++k;
  const auto tail = mc::host::stop_after(p.moves, p.pieces, k, c);
  ASSERT_FALSE(tail.empty());
  EXPECT_TRUE(tail.back().seg.seg.last);
  // 100 mm/s at 0.735 * 2000 mm/s^2 stops in 3.4 mm and 68 ms.
  const double stop_x = double(tail.back().seg.end[0] - p.pieces[k].seg.end[0]) / 400;
  EXPECT_NEAR(stop_x, 100.0 * 100 / (2 * 0.735 * 2000), 0.01);
  EXPECT_NEAR(tail.back().t_end - p.pieces[k].t_end, 100 / (0.735 * 2000), 0.002);
  std::vector<Piece> all(p.pieces.begin(), p.pieces.begin() + long(k) + 1);
  all.insert(all.end(), tail.begin(), tail.end());
  const auto a = mc::host::peak_accel(all, c);
  EXPECT_LE(a[0], 1.01 * 2000);
}

TEST(Planner, RefusesWhatTheMachineCannotDo) {
  PlannerConfig c = config();
  auto refuse = [&](const std::string& prog, const std::string& what) {
    const auto r = mc::gcode::interpret_program(prog, "bad.nc");
    ASSERT_TRUE(r.ok());
    try {
      mc::host::to_moves(r.calls, {}, c, "bad.nc");
      FAIL() << "accepted: " << prog;
    } catch (const mc::host::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refuse("G0 X10\nG1 X400 F100\n", "bad.nc:2: X (machine)");
  refuse("G0 X290\nG2 X290 Y0 I20 J0 F100\n",
         "bad.nc:2: X (machine)");  // both ends inside, the circle is not
  refuse("G38.2 Z-10 F100\n", "bad.nc:1: G38");
  c.axes[2].present = false;
  refuse("G1 X1 Z1 F100\n", "bad.nc:1: Z");
}

TEST(Planner, TheDefaultMachineHasThreeAxesAndItsLimits) {
  const auto m = mc::machine::default_machine();
  ASSERT_EQ(m.axes.size(), 3u);
  const PlannerConfig c = mc::machine::planner_config(m);
  EXPECT_EQ(c.axes[2].max_accel_mm_s2, 1000);
  EXPECT_EQ(c.axes[0].counts_per_mm, 400);
  EXPECT_EQ(c.junction_deviation_mm, 0.01);
  // A job's errors come before anything moves: all of them, with their place.
  try {
    mc::machine::plan_program("G1 X1 F100\nG1 X2 Q\nG5 X1\n", "two.nc", m, {});
    FAIL();
  } catch (const mc::machine::ProgramErrors& e) {
    EXPECT_EQ(e.errors().size(), 2u);
    EXPECT_NE(std::string(e.what()).find("two.nc:2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("two.nc:3:"), std::string::npos) << e.what();
  }
}

}  // namespace

namespace {

// Contour error against an analytic offset: samples that walk a zig-zag of
// 0.1 mm moves (a raster like the surface example) with their measured
// point displaced a known distance across the path.
TEST(Planner, ContourErrorMeasuresTheDistanceAcrossThePath) {
  const PlannerConfig c = config();
  std::ostringstream g;
  g << "G1 F3000\n";
  for (int row = 0; row < 6; ++row) {
    // Z wanders as on a relief, so the walk strays from each chord in 3D.
    for (int i = 1; i <= 100; ++i)
      g << "X" << (row % 2 ? 10 - i * 0.1 : i * 0.1) << " Z" << -0.5 + 0.3 * std::sin(i * 0.37) << "\n";
    g << "Y" << (row + 1) * 1.0 << "\n";
  }
  const Planned p = plan(g.str(), c);
  std::vector<mc::host::JobSample> s;
  const double off = 0.02;  // mm across the rows (along Y), 8 counts
  for (const Piece& x : p.pieces) {
    const Move& m = p.moves[size_t(x.move)];
    const bool on_row = std::fabs(m.end[1] - m.start[1]) < 1e-9;
    // Every count the core visits (the walk strays from the chord by up to
    // a count), as telemetry would sample the command.
    mc::host::walk(x.seg, [&](const mc::host::Vec3& q) {
      mc::host::JobSample js;
      for (size_t k = 0; k < 3; ++k) js.cmd[k] = int32_t(q[k]);
      js.pos = js.cmd;
      if (on_row) js.pos[1] += int32_t(off * 400);
      s.push_back(js);
    });
  }
  const auto e = mc::machine::contour_error(s, p.moves, c);
  EXPECT_EQ(e.n, s.size());
  // Samples on the rows are off by 0.02 mm (or less, near a row's end where
  // the step to the next row is nearer); those on the steps are on the path.
  // (The command itself strays from the path by up to two counts, 5 um.)
  const double strays = 2.0 / 400;
  EXPECT_NEAR(e.max, off, strays);
  EXPECT_NEAR(e.rms, off, 0.2 * off);
  for (auto& js : s) js.pos = js.cmd;
  EXPECT_LT(mc::machine::contour_error(s, p.moves, c).max, strays);
}

}  // namespace
