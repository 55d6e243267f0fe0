#include "host/machine/height_map.hpp"

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "host/base/errors.hpp"

namespace mc::machine {

using gcode::CanonCall;
using gcode::Vec3;
using host::InputError;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string where(const std::string& source, const toml::node& n) {
  return source + ":" + std::to_string(n.source().begin.line) + ": ";
}

}  // namespace

bool HeightMap::contains(double x, double y, double eps) const {
  return x >= x0 - eps && x <= x1() + eps && y >= y0 - eps && y <= y1() + eps;
}

HeightMap::Cell HeightMap::cell(double x, double y) const {
  const double u = std::clamp((x - x0) / dx, 0.0, double(nx - 1));
  const double v = std::clamp((y - y0) / dy, 0.0, double(ny - 1));
  const int i = std::min(int(u), nx - 2), j = std::min(int(v), ny - 2);
  return {i, j, u - i, v - j};
}

double HeightMap::height(double x, double y) const {
  const Cell c = cell(x, y);
  return (1 - c.fv) * ((1 - c.fu) * at(c.i, c.j) + c.fu * at(c.i + 1, c.j)) +
         c.fv * ((1 - c.fu) * at(c.i, c.j + 1) + c.fu * at(c.i + 1, c.j + 1));
}

double HeightMap::twist(int i, int j) const {
  return (at(i + 1, j + 1) - at(i + 1, j) - at(i, j + 1) + at(i, j)) / (dx * dy);
}

HeightMap parse_height_map(std::string_view text, const std::string& source) {
  toml::table doc;
  try {
    doc = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ":" + std::to_string(e.source().begin.line) + ": TOML", "(the file)",
                     "valid TOML", std::string(e.description()));
  }
  const toml::table* m = doc["map"].as_table();
  if (m == nullptr) throw InputError(source + ": [map]", "(none)", "a [map] table", "missing table");
  for (const auto& [key, node] : *m) {
    const std::string k(key.str());
    if (k != "x0_mm" && k != "y0_mm" && k != "dx_mm" && k != "dy_mm" && k != "heights_mm")
      throw InputError(where(source, node) + "map." + k, "(present)",
                       "one of: x0_mm, y0_mm, dx_mm, dy_mm, heights_mm", "unknown key");
  }
  HeightMap map;
  const auto number = [&](const char* key, bool positive) {
    const toml::node* n = m->get(key);
    if (n == nullptr) throw InputError(source + ": map." + key, "(none)", "the key in [map]", "missing key");
    const std::optional<double> v = n->value<double>();
    if (!v || !std::isfinite(*v) || (positive && !(*v > 0)))
      throw InputError(where(source, *n) + "map." + key, v ? host::format_number(*v) : "(not a number)",
                       positive ? "a finite length > 0 mm" : "a finite coordinate in mm");
    return *v;
  };
  map.x0 = number("x0_mm", false);
  map.y0 = number("y0_mm", false);
  map.dx = number("dx_mm", true);
  map.dy = number("dy_mm", true);
  const toml::node* hn = m->get("heights_mm");
  if (hn == nullptr)
    throw InputError(source + ": map.heights_mm", "(none)", "the key in [map]", "missing key");
  const toml::array* rows = hn->as_array();
  if (rows == nullptr || rows->size() < 2)
    throw InputError(where(source, *hn) + "map.heights_mm",
                     rows ? std::to_string(rows->size()) + " rows" : "(not an array)",
                     "an array of at least 2 rows");
  map.ny = int(rows->size());
  for (const toml::node& rn : *rows) {
    const toml::array* row = rn.as_array();
    if (row == nullptr || row->size() < 2)
      throw InputError(where(source, rn) + "map.heights_mm row",
                       row ? std::to_string(row->size()) + " values" : "(not an array)",
                       "an array of at least 2 heights");
    if (map.nx == 0) map.nx = int(row->size());
    if (int(row->size()) != map.nx)
      throw InputError(where(source, rn) + "map.heights_mm row", std::to_string(row->size()) + " values",
                       std::to_string(map.nx) + " values, as the first row");
    for (const toml::node& zn : *row) {
      const std::optional<double> z = zn.value<double>();
      if (!z || !std::isfinite(*z))
        throw InputError(where(source, zn) + "map.heights_mm", z ? host::format_number(*z) : "(not a number)",
                         "a finite height in mm");
      map.z.push_back(*z);
    }
  }
  return map;
}

HeightMap load_height_map(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("--level", host::quote(path), "a readable height map file (TOML)", "cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_height_map(s.str(), path);
}

namespace {
// The grid's geometry as the double it is, so that the map's edges read back
// where they were (heights keep 6 decimals: nanometres).
std::string exact(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  std::string t = b;
  if (t.find_first_of(".en") == std::string::npos) t += ".0";  // a TOML float, not an integer
  return t;
}
}  // namespace

std::string format_height_map(const HeightMap& map) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(6);
  s << "# Bed height map (docs/levelling.md): heights in mm relative to the first point,\n"
    << "# one row per Y from y0_mm up, one value per X from x0_mm up.\n[map]\n"
    << "x0_mm = " << exact(map.x0) << "\ny0_mm = " << exact(map.y0) << "\ndx_mm = " << exact(map.dx)
    << "\ndy_mm = " << exact(map.dy) << "\nheights_mm = [\n";
  for (int j = 0; j < map.ny; ++j) {
    s << "  [";
    for (int i = 0; i < map.nx; ++i) s << (i ? ", " : "") << map.at(i, j);
    s << "],\n";
  }
  s << "]\n";
  return s.str();
}

namespace {

// Walks the calls with the program's (unlevelled) position and writes the
// levelled ones.
class Leveler {
 public:
  Leveler(const HeightMap& map, const LevelOptions& o, const std::string& file, bool split)
      : map_(map), tol_(o.tolerance_mm), file_(file), split_(split) {
    if (!(tol_ > 0) || !std::isfinite(tol_))
      throw InputError("levelling tolerance", host::format_number(tol_), "a finite length > 0 mm");
  }

  std::vector<CanonCall> run(const std::vector<CanonCall>& calls, const Vec3& start) {
    pos_ = start;
    for (const CanonCall& c : calls) {
      line_ = c.line;
      std::visit([&](const auto& op) { apply(c, op); }, c.op);
    }
    return std::move(out_);
  }

 private:
  const HeightMap& map_;
  double tol_;
  const std::string& file_;
  bool split_;
  Vec3 pos_{};
  int line_ = 0;
  std::vector<CanonCall> out_;

  Vec3 levelled(const Vec3& p) const { return {p[0], p[1], p[2] + map_.height(p[0], p[1])}; }
  std::string place() const { return (file_.empty() ? "line " : file_ + ":") + std::to_string(line_); }

  void require_inside(const Vec3& p) const {
    if (map_.contains(p[0], p[1], 1e-3)) return;  // a micron: printed maps and programs round
    const auto mm = [](double v) { return host::format_number(std::round(v * 1e3) / 1e3); };  // to a micron
    throw InputError(place() + ": cut at X" + mm(p[0]) + " Y" + mm(p[1]), "outside the height map",
                     "X " + host::format_number(map_.x0) + ".." + host::format_number(map_.x1()) + ", Y " +
                         host::format_number(map_.y0) + ".." + host::format_number(map_.y1()),
                     "the map says nothing there: probe a larger area");
  }

  void apply(const CanonCall& c, const gcode::StraightTraverse& op) {
    out_.push_back({c.line, gcode::StraightTraverse{levelled(op.end)}});
    pos_ = op.end;
  }
  void apply(const CanonCall&, const gcode::StraightFeed& op) {
    require_inside(pos_);
    require_inside(op.end);
    feed_line(pos_, op.end, op.feed_mm_min);
    pos_ = op.end;
  }
  void apply(const CanonCall&, const gcode::ArcFeed& op) {
    const gcode::PlaneAxes ax = gcode::plane_axes(op.plane);
    const double sweep = gcode::arc_sweep(pos_, op);
    const double a0 =
        std::atan2(pos_[ax.second] - op.centre[ax.second], pos_[ax.first] - op.centre[ax.first]);
    const double r0 =
        std::hypot(pos_[ax.first] - op.centre[ax.first], pos_[ax.second] - op.centre[ax.second]);
    const double r1 =
        std::hypot(op.end[ax.first] - op.centre[ax.first], op.end[ax.second] - op.centre[ax.second]);
    const double r = std::max(r0, r1);
    // Chords within the tolerance: the sagitta r (1 - cos(step / 2)) <= tol.
    const double step = tol_ < r ? 2 * std::acos(1 - tol_ / r) : kPi / 2;
    const int n = std::max(1, int(std::ceil(sweep / step)));
    const double sign = op.clockwise ? -1.0 : 1.0;
    Vec3 from = pos_;
    for (int k = 1; k <= n; ++k) {
      Vec3 p = op.end;
      if (k < n) {
        const double f = double(k) / n, a = a0 + sign * sweep * f, rr = r0 + (r1 - r0) * f;
        p[ax.first] = op.centre[ax.first] + rr * std::cos(a);
        p[ax.second] = op.centre[ax.second] + rr * std::sin(a);
        p[ax.normal] = pos_[ax.normal] + (op.end[ax.normal] - pos_[ax.normal]) * f;
      }
      require_inside(p);
      feed_line(from, p, op.feed_mm_min);
      from = p;
    }
    pos_ = op.end;
  }
  void apply(const CanonCall&, const gcode::StraightProbe&) {
    throw InputError(place() + ": G38 probe", "in a levelled job", "a job without probing moves",
                     "a probe's stop point is unknown beforehand, so the rest cannot be levelled");
  }
  // Everything that does not move: as it is.
  template <class Op>
  void apply(const CanonCall& c, const Op&) {
    out_.push_back(c);
  }

  // The straight feed a..b, levelled: split at grid lines, then where the
  // cell's twist bends the surface more than the tolerance off the chord.
  void feed_line(const Vec3& a, const Vec3& b, double feed) {
    const auto emit = [&](const Vec3& p) { out_.push_back({line_, gcode::StraightFeed{levelled(p), feed}}); };
    if (!split_) {
      emit(b);
      return;
    }
    std::vector<double> ts = {0.0, 1.0};
    const auto crossings = [&](int axis, double origin, double spacing, int n) {
      const double d = b[axis] - a[axis];
      if (d == 0) return;
      for (int k = 1; k < n - 1; ++k) {
        const double t = (origin + spacing * k - a[axis]) / d;
        if (t > 1e-12 && t < 1 - 1e-12) ts.push_back(t);
      }
    };
    crossings(0, map_.x0, map_.dx, map_.nx);
    crossings(1, map_.y0, map_.dy, map_.ny);
    std::sort(ts.begin(), ts.end());
    const auto at = [&](double t) {
      return Vec3{a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
    };
    for (size_t k = 1; k < ts.size(); ++k) {
      const double t0 = ts[k - 1], t1 = ts[k];
      if (t1 - t0 < 1e-12) continue;
      // Along a straight piece in one cell the bilinear height is quadratic
      // in t, c t^2 + ...: the chord is off it by at most |c| / 4.
      const Vec3 mid = at((t0 + t1) / 2);
      const HeightMap::Cell in = map_.cell(mid[0], mid[1]);
      const double twist = map_.twist(in.i, in.j);
      const double c = twist * (b[0] - a[0]) * (t1 - t0) * (b[1] - a[1]) * (t1 - t0);
      const int n = std::max(1, int(std::ceil(std::sqrt(std::abs(c) / (4 * tol_)))));
      for (int q = 1; q <= n; ++q) emit(q == n && k + 1 == ts.size() ? b : at(t0 + (t1 - t0) * q / n));
    }
  }
};

}  // namespace

std::vector<CanonCall> level_calls(const std::vector<CanonCall>& calls, const Vec3& start,
                                   const HeightMap& map, const LevelOptions& options,
                                   const std::string& file) {
  return Leveler(map, options, file, true).run(calls, start);
}

std::vector<CanonCall> level_calls_endpoints(const std::vector<CanonCall>& calls, const Vec3& start,
                                             const HeightMap& map, const LevelOptions& options,
                                             const std::string& file) {
  return Leveler(map, options, file, false).run(calls, start);
}

}  // namespace mc::machine
