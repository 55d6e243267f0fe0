// The workpiece of the machine TOML (host/machine/workpiece): its face
// against the shape the keys describe, the height map a perfect probe would
// take, the engraving program of the levelling comparison, and the depth
// error of a measured path.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "host/base/errors.hpp"
#include "host/machine/job.hpp"
#include "host/machine/machine_config.hpp"
#include "host/machine/workpiece.hpp"

namespace mc::machine {
namespace {

WorkpieceConfig plate(double noise_m = 0) {
  WorkpieceConfig w;
  w.min_x_m = 0.01;
  w.min_y_m = -0.02;
  w.max_x_m = 0.21;
  w.max_y_m = 0.13;
  w.top_z_m = -0.004;
  w.tilt_x = 0.0025;
  w.tilt_y = -0.001;
  w.bow_m = 0.0002;
  w.noise_m = noise_m;
  return w;
}

TEST(Workpiece, TheFaceIsThePlaneMinusTheDishPlusTheRoughness) {
  const WorkpieceConfig w = plate();
  EXPECT_NEAR(surface_z_mm(w, 10, -20), -4.0,
              1e-12);  // the min corner: the plane's origin, no dish at an edge
  EXPECT_NEAR(surface_z_mm(w, 210, -20), -4.0 + 0.5, 1e-12);
  EXPECT_NEAR(surface_z_mm(w, 10, 130), -4.0 - 0.15, 1e-12);
  EXPECT_NEAR(surface_z_mm(w, 110, 55), -4.0 + 0.25 - 0.075 - 0.2, 1e-12);  // the middle: the whole dish
  // Roughness: RMS as configured, the same for the same seed, another for another.
  const WorkpieceConfig r = plate(2e-6);
  double sum2 = 0;
  int n = 0;
  for (int i = 0; i <= 540; ++i)
    for (int k = 0; k <= 365; ++k, ++n) {
      const double x = 10 + 0.37 * i, y = -20 + 0.41 * k;
      const double d = surface_z_mm(r, x, y) - surface_z_mm(w, x, y);
      sum2 += d * d;
    }
  EXPECT_NEAR(std::sqrt(sum2 / n) * 1e3, 2.0, 0.25);  // um
  WorkpieceConfig other = r;
  other.noise_seed = 2;
  EXPECT_EQ(surface_z_mm(r, 57.3, 12.9), surface_z_mm(plate(2e-6), 57.3, 12.9));
  EXPECT_NE(surface_z_mm(r, 57.3, 12.9), surface_z_mm(other, 57.3, 12.9));
}

// The virtual probe's cache gives surface_z_mm's values bit for bit along
// a path that crosses roughness cells both ways, and no point of a box
// lies farther from the face at its centre than variation_mm says (in and
// off the plate, where the dish's slope grows).
TEST(Workpiece, TheCacheGivesTheSameFaceAndTheVariationBoundsIt) {
  const WorkpieceConfig w = plate(5e-6);
  SurfaceCache c(w);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> along(-60, 300), tiny(0, 0.01), unit(-1, 1);
  double x = 40, y = 30;
  for (int i = 0; i < 20000; ++i) {
    x += 0.3 * unit(rng) + 0.05;  // mostly within a 5 mm cell, now and then into the next
    y += 0.3 * unit(rng) - 0.02;
    ASSERT_EQ(c.z_mm(x, y), surface_z_mm(w, x, y)) << x << ", " << y;
  }
  double tightest = 1e9;
  for (int i = 0; i < 2000; ++i) {
    const double x0 = along(rng), y0 = along(rng), dx = tiny(rng), dy = tiny(rng);
    const double z0 = surface_z_mm(w, x0, y0), bound = c.variation_mm(x0, y0, dx, dy);
    double most = 0;
    for (int k = 0; k < 40; ++k) {
      const double d = std::fabs(surface_z_mm(w, x0 + dx * unit(rng), y0 + dy * unit(rng)) - z0);
      ASSERT_LE(d, bound) << x0 << ", " << y0 << " +- " << dx << ", " << dy;
      most = std::max(most, d);
    }
    if (most > 0) tightest = std::min(tightest, bound / most);
  }
  // Not loose everywhere: somewhere it comes within 20x of what the
  // samples found (printed).
  std::printf("variation_mm: at best %.2f x the largest sampled change\n", tightest);
  EXPECT_LT(tightest, 20);
}

TEST(Workpiece, TheDefaultMachineHasOneAndBadKeysAreRefusedWithTheirLine) {
  const MachineConfig m = default_machine();
  ASSERT_TRUE(m.workpiece.has_value());
  EXPECT_NEAR(surface_z_mm(*m.workpiece, 200, 0) - surface_z_mm(*m.workpiece, 0, 0), 0.5, 0.01);
  std::string text(default_machine_toml());
  const std::string key = "tilt_x = 0.0025";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, key.size(), "tilt_x = 0.5");
  try {
    parse_machine(text, "m.toml");
    FAIL() << "a 0.5 m/m tilt was accepted";
  } catch (const host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("workpiece.tilt_x = 0.5"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("m.toml:", 0), 0u) << e.what();
  }
}

TEST(Workpiece, APerfectProbesMapHoldsTheFaceRelativeToItsFirstPoint) {
  const WorkpieceConfig w = plate(1e-6);
  const HeightMap m = sample_height_map(w, 5, 4, 5);
  EXPECT_NEAR(m.x0, 15, 1e-12);
  EXPECT_NEAR(m.x1(), 205, 1e-12);
  EXPECT_NEAR(m.y0, -15, 1e-12);
  EXPECT_NEAR(m.y1(), 125, 1e-12);
  EXPECT_EQ(m.at(0, 0), 0);
  const double z0 = surface_z_mm(w, 15, -15);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i)
      EXPECT_NEAR(m.at(i, j), surface_z_mm(w, m.x0 + i * m.dx, m.y0 + j * m.dy) - z0, 1e-12);
  EXPECT_THROW(sample_height_map(w, 1, 4, 5), host::InputError);
}

TEST(Workpiece, TheEngravingRunsLevelledOverTheMapAndItsDepthErrorIsMeasuredOnCuts) {
  MachineConfig mc = default_machine();
  mc.workpiece = plate();
  const WorkpieceConfig& w = *mc.workpiece;
  const HeightMap map = sample_height_map(w, 9, 7, 5);
  const std::string prog = engraving_program(map, surface_z_mm(w, map.x0, map.y0), 0.1, 1500, 3, 2);
  const Job j = plan_program(prog, "engrave.nc", mc, {0, 0, 0}, &map);
  EXPECT_GT(j.summary.moves, 20);
  // Samples: a cut at the right depth, one 0.01 mm too shallow, a rapid
  // (above the cuts: not counted) and a plunge (XY standing: not counted).
  const mc::host::PlannerConfig& cfg = j.cfg;
  const double zs = surface_z_mm(w, 100, 50);
  const auto at = [&](double x, double y, double z) {
    return std::array<int32_t, 3>{int32_t(std::lround(x * cfg.axes[0].counts_per_mm)),
                                  int32_t(std::lround(y * cfg.axes[1].counts_per_mm)),
                                  int32_t(std::lround(z * cfg.axes[2].counts_per_mm))};
  };
  std::vector<mc::host::JobSample> s(5);
  s[0].cmd = s[0].pos = at(99, 50, zs - 0.1);
  s[1].cmd = s[1].pos = at(100, 50, zs - 0.1);
  s[2].cmd = at(101, 50, zs - 0.1);
  s[2].pos = at(100, 50, zs - 0.09);
  s[3].cmd = s[3].pos = at(102, 50, zs + 3);
  s[4].cmd = s[4].pos = at(102, 50, zs - 0.05);
  const DepthStats d = depth_error(s, cfg, w, map, 0.1);
  EXPECT_EQ(d.n, 2u);
  const double count = 1 / cfg.axes[2].counts_per_mm;
  EXPECT_NEAR(d.worst_mm, 0.01, count);
  EXPECT_NEAR(d.max_mm, 0.01, count);
  EXPECT_LE(std::abs(d.min_mm), count);
}

}  // namespace
}  // namespace mc::machine
