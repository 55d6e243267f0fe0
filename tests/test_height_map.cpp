// Bed levelling (host/machine/height_map): the map file, bilinear heights,
// and programs deformed by a map. The levelled path is checked against the
// map itself: every piece inside one cell, on the programmed XY path, within
// the tolerance of the bilinear surface everywhere along it; and against a
// surface the bilinear interpolation reproduces exactly (a twisted plane),
// where the levelled Z must equal programmed Z + surface at every point.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "host/base/errors.hpp"
#include "host/gcode/canon.hpp"
#include "host/machine/height_map.hpp"

namespace mc::machine {
namespace {

using gcode::CanonCall;
using gcode::Vec3;

HeightMap grid(int nx, int ny, double x0, double y0, double dx, double dy,
               const std::function<double(double, double)>& f) {
  HeightMap m;
  m.x0 = x0;
  m.y0 = y0;
  m.dx = dx;
  m.dy = dy;
  m.nx = nx;
  m.ny = ny;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.z.push_back(f(x0 + i * dx, y0 + j * dy));
  return m;
}

// A tilted, bowed bed with a bump: what bilinear interpolation cannot
// reproduce exactly.
double bed(double x, double y) {
  return 0.5 * x / 200 - 0.2 * (1 - std::pow((x - 100) / 100, 2)) * (1 - std::pow((y - 75) / 75, 2)) +
         0.01 * std::sin(x / 7) * std::cos(y / 9);
}

Vec3 end_of(const CanonCall& c) {
  if (const auto* f = std::get_if<gcode::StraightFeed>(&c.op)) return f->end;
  if (const auto* t = std::get_if<gcode::StraightTraverse>(&c.op)) return t->end;
  ADD_FAILURE() << "not a straight move: " << gcode::to_string(c);
  return {};
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const host::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(HeightMap, ParsesWhatItFormats) {
  const HeightMap m = grid(4, 3, -10, 5, 12.5, 20, bed);
  const HeightMap back = parse_height_map(format_height_map(m), "map.toml");
  EXPECT_EQ(back.nx, 4);
  EXPECT_EQ(back.ny, 3);
  EXPECT_EQ(back.x0, -10);
  EXPECT_EQ(back.dy, 20);
  // The edges read back exactly, whatever the spacing.
  const HeightMap thirds = grid(7, 2, 5, 5, 190.0 / 6, 140.0 / 6, bed);
  const HeightMap t = parse_height_map(format_height_map(thirds), "map.toml");
  EXPECT_EQ(t.x1(), thirds.x1());
  EXPECT_EQ(t.dy, thirds.dy);
  for (size_t k = 0; k < m.z.size(); ++k) EXPECT_NEAR(back.z[k], m.z[k], 5e-7);
}

TEST(HeightMap, RefusesBadFilesWithFileAndLine) {
  const std::string head = "[map]\nx0_mm = 0\ny0_mm = 0\ndx_mm = 10\ndy_mm = 10\n";
  EXPECT_NE(message_of([&] {
              parse_height_map(head + "heights_mm = [[0, 1], [0]]\n", "m.toml");
            }).find("m.toml:6: map.heights_mm row = 1 values"),
            std::string::npos);
  EXPECT_NE(
      message_of([&] { parse_height_map(head + "heights_mm = [[0, 1]]\n", "m.toml"); }).find("m.toml:6:"),
      std::string::npos);
  EXPECT_NE(message_of([&] {
              parse_height_map(
                  "[map]\nx0_mm = 0\ny0_mm = 0\ndx_mm = -1\ndy_mm = 10\nheights_mm = [[0,0],[0,0]]\n",
                  "m.toml");
            }).find("m.toml:4: map.dx_mm = -1"),
            std::string::npos);
  EXPECT_NE(message_of([&] {
              parse_height_map(head + "heights_mm = [[0, nan], [0, 0]]\n", "m.toml");
            }).find("finite height"),
            std::string::npos);
  EXPECT_NE(message_of([&] {
              parse_height_map(head + "heights_mm = [[0,0],[0,0]]\nspacing = 3\n", "m.toml");
            }).find("m.toml:7: map.spacing"),
            std::string::npos);
  EXPECT_NE(message_of([&] { parse_height_map(head, "m.toml"); }).find("map.heights_mm = (none)"),
            std::string::npos);
  EXPECT_NE(message_of([&] { parse_height_map("[map\n", "m.toml"); }).find("m.toml:1: TOML"),
            std::string::npos);
}

TEST(HeightMap, BilinearIsExactOnATwistedPlaneAndClampsOutside) {
  const auto twisted = [](double x, double y) { return 0.1 + 0.002 * x - 0.003 * y + 1e-5 * x * y; };
  const HeightMap m = grid(5, 4, 0, 0, 25, 30, twisted);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0, 100), uy(0, 90);
  for (int k = 0; k < 1000; ++k) {
    const double x = ux(rng), y = uy(rng);
    EXPECT_NEAR(m.height(x, y), twisted(x, y), 1e-12);
  }
  EXPECT_NEAR(m.height(-50, 45), twisted(0, 45), 1e-12);
  EXPECT_NEAR(m.height(130, 200), twisted(100, 90), 1e-12);
}

// Random straight feeds inside a 200 x 150 mm map of the bed.
TEST(HeightMap, LevelledLinesStayInOneCellOnThePathAndWithinTheTolerance) {
  const HeightMap m = grid(9, 7, 0, 0, 25, 25, bed);
  const double tol = 0.002;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0, 200), uy(0, 150), uz(-1, 0);
  for (int trial = 0; trial < 300; ++trial) {
    const Vec3 a{ux(rng), uy(rng), uz(rng)}, b{ux(rng), uy(rng), uz(rng)};
    const std::vector<CanonCall> out =
        level_calls({{7, gcode::StraightFeed{b, 600}}}, a, m, LevelOptions{tol}, "job.nc");
    ASSERT_FALSE(out.empty());
    Vec3 from = a;
    from[2] += m.height(a[0], a[1]);
    for (const CanonCall& c : out) {
      EXPECT_EQ(c.line, 7);
      const Vec3 to = end_of(c);
      // One cell: the piece's midpoint's cell holds both ends.
      const double mu = ((from[0] + to[0]) / 2) / m.dx, mv = ((from[1] + to[1]) / 2) / m.dy;
      const double i = std::floor(mu), j = std::floor(mv);
      for (const Vec3& p : {from, to}) {
        EXPECT_GE(p[0] / m.dx, i - 1e-9);
        EXPECT_LE(p[0] / m.dx, i + 1 + 1e-9);
        EXPECT_GE(p[1] / m.dy, j - 1e-9);
        EXPECT_LE(p[1] / m.dy, j + 1 + 1e-9);
      }
      // On the programmed path, and within the tolerance of path + surface.
      for (int s = 0; s <= 16; ++s) {
        const double f = s / 16.0;
        const Vec3 p{from[0] + (to[0] - from[0]) * f, from[1] + (to[1] - from[1]) * f,
                     from[2] + (to[2] - from[2]) * f};
        const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
        const double t = len > 0 ? std::hypot(p[0] - a[0], p[1] - a[1]) / len : 0;
        const double cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        ASSERT_LE(std::abs(cross) / std::max(len, 1e-9), 1e-9) << "off the XY path";
        const double want = a[2] + (b[2] - a[2]) * t + m.height(p[0], p[1]);
        ASSERT_LE(std::abs(p[2] - want), tol + 1e-9) << "trial " << trial;
      }
      from = to;
    }
    const Vec3 last = end_of(out.back());
    EXPECT_EQ(last[0], b[0]);
    EXPECT_EQ(last[1], b[1]);
    EXPECT_NEAR(last[2], b[2] + m.height(b[0], b[1]), 1e-12);
  }
}

TEST(HeightMap, OnASurfaceItReproducesTheLevelledZIsExact) {
  const auto twisted = [](double x, double y) { return 0.05 + 0.001 * x + 0.002 * y - 2e-5 * x * y; };
  const HeightMap m = grid(5, 5, 0, 0, 50, 50, twisted);
  const Vec3 a{3, 7, -0.1}, b{191, 163, -0.1};
  for (const CanonCall& c : level_calls({{1, gcode::StraightFeed{b, 600}}}, a, m)) {
    const Vec3 p = end_of(c);
    EXPECT_NEAR(p[2], -0.1 + twisted(p[0], p[1]), 1e-12);
  }
}

TEST(HeightMap, ArcsBecomeLevelledChordsWithinTheTolerance) {
  const HeightMap m = grid(9, 7, 0, 0, 25, 25, bed);
  const double tol = 0.002;
  for (bool cw : {false, true}) {
    const Vec3 start{150, 75, -0.2};
    gcode::ArcFeed arc{{150, 75, -0.2}, {100, 75, -0.2}, gcode::Plane::xy, cw, 1, 900};  // a full circle
    const std::vector<CanonCall> out = level_calls({{3, arc}}, start, m, LevelOptions{tol});
    ASSERT_GT(out.size(), 100u);
    for (const CanonCall& c : out) {
      const Vec3 p = end_of(c);
      // On a chord of the circle (split further at grid lines): inside it
      // by at most the tolerance.
      const double r = std::hypot(p[0] - 100, p[1] - 75);
      EXPECT_LE(r, 50 + 1e-9);
      EXPECT_GE(r, 50 - tol - 1e-9);
      EXPECT_NEAR(p[2], -0.2 + m.height(p[0], p[1]), 1e-12);
    }
  }
}

TEST(HeightMap, RefusesCutsOutsideTheMapAndProbesButLevelsRapidsAtTheEdge) {
  const HeightMap m = grid(3, 3, 0, 0, 50, 50, bed);
  const std::string out_msg = message_of([&] {
    level_calls({{12, gcode::StraightFeed{{120, 50, 0}, 300}}}, {50, 50, 0}, m, {}, "job.nc");
  });
  EXPECT_NE(out_msg.find("job.nc:12: cut at X120 Y50"), std::string::npos) << out_msg;
  EXPECT_NE(out_msg.find("X 0..100, Y 0..100"), std::string::npos) << out_msg;
  EXPECT_NE(message_of([&] {
              level_calls({{4, gcode::StraightProbe{{0, 0, -5}, gcode::ProbeMode::toward_error, 100}}},
                          {0, 0, 0}, m);
            }).find("line 4: G38 probe"),
            std::string::npos);
  const std::vector<CanonCall> r = level_calls({{1, gcode::StraightTraverse{{150, -20, 5}}}}, {0, 0, 5}, m);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(end_of(r[0])[2], 5 + m.at(2, 0), 1e-12);
}

// The paper's method offsets only each move's end points; on a bowed bed the
// middle of a long cut is then off by the bow, where the split path is not.
TEST(HeightMap, EndPointOnlyLevellingMissesTheBowInTheMiddleOfACut) {
  const HeightMap m = grid(9, 7, 0, 0, 25, 25, bed);
  const Vec3 a{0, 75, -0.1}, b{200, 75, -0.1};
  const std::vector<CanonCall> ends = level_calls_endpoints({{1, gcode::StraightFeed{b, 600}}}, a, m);
  ASSERT_EQ(ends.size(), 1u);
  const Vec3 e = end_of(ends[0]);
  const double z_mid_ends = ((a[2] + m.height(a[0], a[1])) + e[2]) / 2;
  const double want_mid = -0.1 + m.height(100, 75);
  EXPECT_GT(std::abs(z_mid_ends - want_mid), 0.15);  // the bow is 0.2 mm
  const std::vector<CanonCall> split = level_calls({{1, gcode::StraightFeed{b, 600}}}, a, m);
  EXPECT_EQ(split.size(), 8u);  // one piece per cell crossed
}

}  // namespace
}  // namespace mc::machine
