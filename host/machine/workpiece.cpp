#include "host/machine/workpiece.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

#include "host/base/errors.hpp"

namespace mc::machine {
namespace {

constexpr double kLatticeMm = 5.0;  // the roughness's correlation length
constexpr double kSafeMm = 3.0;     // rapids this far above the work zero

// A value of unit variance for lattice point (i, j): a hash of the seed and
// the point to a uniform in [-sqrt 3, sqrt 3].
double lattice(int seed, int64_t i, int64_t j) {
  uint64_t h = uint64_t(seed) * 0x9E3779B97F4A7C15ull ^ uint64_t(i) * 0xC2B2AE3D27D4EB4Full ^
               uint64_t(j) * 0x165667B19E3779F9ull;
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  const double u = double(h >> 11) * 0x1.0p-53;  // [0, 1)
  return (2 * u - 1) * std::sqrt(3.0);
}

std::string mm(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4f", v);
  return b;
}

// A point on the plate: machine X, Y (m), and where it lies between the
// plate's edges, u and v (-1 to 1 on the plate), with the half widths
// hx, hy (m): the dish is b (1 - u^2)(1 - v^2).
struct PlatePoint {
  double x, y, u, v, hx, hy;
};
PlatePoint plate_point(const WorkpieceConfig& w, double x_mm, double y_mm) {
  PlatePoint p;
  p.x = x_mm * 1e-3;
  p.y = y_mm * 1e-3;
  p.hx = (w.max_x_m - w.min_x_m) / 2;
  p.hy = (w.max_y_m - w.min_y_m) / 2;
  p.u = (p.x - (w.min_x_m + p.hx)) / p.hx;
  p.v = (p.y - (w.min_y_m + p.hy)) / p.hy;
  return p;
}

// The face at (x, y), the lattice values taken from `cell` (filled in when
// it holds another cell's).
double face_z_mm(const WorkpieceConfig& w, double x_mm, double y_mm, SurfaceCache::Cell& cell) {
  const PlatePoint p = plate_point(w, x_mm, y_mm);
  const double u = p.u, v = p.v;
  double z = w.top_z_m + w.tilt_x * (p.x - w.min_x_m) + w.tilt_y * (p.y - w.min_y_m) -
             w.bow_m * (1 - u * u) * (1 - v * v);
  if (w.noise_m > 0) {
    // Bilinear between independent unit values averages their variance
    // down to 4/9 over a cell: 3/2 brings the RMS back to noise_m.
    const double gx = x_mm / kLatticeMm, gy = y_mm / kLatticeMm;
    const auto i = int64_t(std::floor(gx)), j = int64_t(std::floor(gy));
    if (!cell.set || cell.i != i || cell.j != j) {
      const int s = w.noise_seed;
      cell = {i,
              j,
              {lattice(s, i, j), lattice(s, i + 1, j), lattice(s, i, j + 1), lattice(s, i + 1, j + 1)},
              true};
    }
    const double fx = gx - double(i), fy = gy - double(j);
    const double* c = cell.v;
    const double n = (1 - fy) * ((1 - fx) * c[0] + fx * c[1]) + fy * ((1 - fx) * c[2] + fx * c[3]);
    z += 1.5 * w.noise_m * n;
  }
  return z * 1e3;
}

}  // namespace

double surface_z_mm(const WorkpieceConfig& w, double x_mm, double y_mm) {
  SurfaceCache::Cell cell;
  return face_z_mm(w, x_mm, y_mm, cell);
}

double SurfaceCache::z_mm(double x_mm, double y_mm) {
  return face_z_mm(w_, x_mm, y_mm, cell_);
}

double SurfaceCache::variation_mm(double x_mm, double y_mm, double dx_mm, double dy_mm) const {
  const WorkpieceConfig& w = w_;
  const PlatePoint p = plate_point(w, x_mm, y_mm);
  const double du = dx_mm * 1e-3 / p.hx, dv = dy_mm * 1e-3 / p.hy;
  const double u = std::fabs(p.u) + du, v = std::fabs(p.v) + dv;  // the most |u|, |v| in the box
  // Plane; dish b (1 - u^2)(1 - v^2), |u1^2 - u0^2| <= 2 u du; roughness,
  // bilinear between values within +-sqrt 3: at most 2 sqrt 3 a lattice
  // step along each axis.
  const double plane = std::fabs(w.tilt_x) * dx_mm + std::fabs(w.tilt_y) * dy_mm;
  const double dish = std::fabs(w.bow_m) * 1e3 * (2 * u * du * (1 + v * v) + (1 + u * u) * 2 * v * dv);
  const double rough = 1.5 * w.noise_m * 1e3 * 2 * std::sqrt(3.0) * (dx_mm + dy_mm) / kLatticeMm;
  return (plane + dish + rough) * (1 + 1e-9) + 1e-9;
}

HeightMap sample_height_map(const WorkpieceConfig& w, int nx, int ny, double inset_mm) {
  if (nx < 2 || ny < 2)
    throw host::InputError("height map points", std::to_string(nx) + "x" + std::to_string(ny),
                           "at least 2x2");
  HeightMap m;
  m.nx = nx;
  m.ny = ny;
  m.x0 = w.min_x_m * 1e3 + inset_mm;
  m.y0 = w.min_y_m * 1e3 + inset_mm;
  m.dx = ((w.max_x_m - w.min_x_m) * 1e3 - 2 * inset_mm) / (nx - 1);
  m.dy = ((w.max_y_m - w.min_y_m) * 1e3 - 2 * inset_mm) / (ny - 1);
  if (!(m.dx > 0) || !(m.dy > 0))
    throw host::InputError("height map inset", host::format_number(inset_mm) + " mm",
                           "less than half the workpiece's size");
  const double z0 = surface_z_mm(w, m.x0, m.y0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.z.push_back(surface_z_mm(w, m.x0 + i * m.dx, m.y0 + j * m.dy) - z0);
  return m;
}

std::string engraving_program(const HeightMap& map, double work_zero_z_mm, double depth_mm,
                              double feed_mm_min, int rows, int columns) {
  std::ostringstream g;
  g << "(An engraving " << mm(depth_mm) << " mm deep over the workpiece: " << rows << " cuts along X, "
    << columns << " along Y.)\n"
    << "(Work zero: the face at the map's first point, X" << mm(map.x0) << " Y" << mm(map.y0) << ".)\n"
    << "G21 G90 G17 G94\n"
    << "G10 L2 P1 X0 Y0 Z" << mm(work_zero_z_mm) << "\nG54\nG0 Z" << mm(kSafeMm) << "\n";
  const auto cut = [&](double xa, double ya, double xb, double yb) {
    // The dwell lets the Z servo settle from the plunge, which it overshoots
    // by a few counts: this compares levelling, not plunges.
    g << "G0 X" << mm(xa) << " Y" << mm(ya) << "\nG1 Z" << mm(-depth_mm) << " F300\nG4 P0.25\nG1 X" << mm(xb)
      << " Y" << mm(yb) << " F" << mm(feed_mm_min) << "\nG0 Z" << mm(kSafeMm) << "\n";
  };
  for (int j = 0; j < rows; ++j) {
    const double y = map.y0 + (map.y1() - map.y0) * (j + 0.5) / rows;
    if (j % 2 == 0)
      cut(map.x0, y, map.x1(), y);
    else
      cut(map.x1(), y, map.x0, y);
  }
  for (int i = 0; i < columns; ++i) {
    const double x = map.x0 + (map.x1() - map.x0) * (i + 0.5) / columns;
    if (i % 2 == 0)
      cut(x, map.y1(), x, map.y0);
    else
      cut(x, map.y0, x, map.y1());
  }
  g << "G0 X" << mm(map.x0) << " Y" << mm(map.y0) << "\nM2\n";
  return g.str();
}

DepthStats depth_error(const std::vector<mc::host::JobSample>& samples, const mc::host::PlannerConfig& cfg,
                       const WorkpieceConfig& w, const HeightMap& map, double depth_mm) {
  DepthStats st;
  const double zs0 = surface_z_mm(w, map.x0, map.y0);
  double sum2 = 0;
  for (size_t k = 1; k < samples.size(); ++k) {
    const auto& s = samples[k];
    const auto& prev = samples[k - 1];
    // A cut: the command moving in XY below the rapids' level.
    if (s.cmd[0] == prev.cmd[0] && s.cmd[1] == prev.cmd[1]) continue;
    const mc::host::Vec3d cmd = mc::host::to_mm(mc::host::Vec3{s.cmd[0], s.cmd[1], s.cmd[2]}, cfg);
    if (cmd[2] > zs0 + kSafeMm / 2) continue;
    const mc::host::Vec3d p = mc::host::to_mm(mc::host::Vec3{s.pos[0], s.pos[1], s.pos[2]}, cfg);
    const double e = p[2] - (surface_z_mm(w, p[0], p[1]) - depth_mm);
    sum2 += e * e;
    st.max_mm = std::max(st.max_mm, std::abs(e));
    st.min_mm = st.n ? std::min(st.min_mm, e) : e;
    st.worst_mm = st.n ? std::max(st.worst_mm, e) : e;
    ++st.n;
  }
  st.rms_mm = st.n ? std::sqrt(sum2 / double(st.n)) : 0;
  return st;
}

}  // namespace mc::machine
