#include "host/machine/limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hls/board_regs.hpp"
#include "hls/pid_regs.hpp"
#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"

namespace mc::machine {

using mc::host::format_number;
using mc::host::InputError;
using mc::host::quote;
using mc::host::Vec3;

namespace {

constexpr uint32_t kFerrMax = 0xFFFF;  // FERR [15:0]

std::string mm(double metres) {
  return format_number(metres * 1e3) + " mm";
}

std::string value_of(const Asked& a, const std::string& fallback) {
  return a.as_written.empty() ? fallback : quote(a.as_written);
}

size_t axes_of(const MachineConfig& m) {
  return std::min<size_t>(m.axes.size(), 3);
}

}  // namespace

void check_travel(const MachineConfig& m, const Vec3& from, const Vec3& to, const Asked& asked) {
  for (size_t a = 0; a < axes_of(m); ++a) {
    const AxisConfig& ax = m.axes[a];
    const double cpm = counts_per_m(ax);
    const double at = double(to[a]) / cpm;
    if (at >= ax.travel_min_m - 0.5 / cpm && at <= ax.travel_max_m + 0.5 / cpm) continue;
    throw InputError(std::string(asked.option), value_of(asked, mm(at)),
                     "a move that ends within axis " + ax.name + "'s travel " + mm(ax.travel_min_m) + ".." +
                         mm(ax.travel_max_m) + " (travel_min_m, travel_max_m in " + m.source + ")",
                     "axis " + ax.name + " would end at " + mm(at) + ", from " + mm(double(from[a]) / cpm));
  }
}

double max_feed_mm_min(const MachineConfig& m, const Vec3& from, const Vec3& to) {
  std::array<double, 3> d{};
  double path = 0;
  for (size_t a = 0; a < axes_of(m); ++a) {
    d[a] = double(to[a] - from[a]) / counts_per_m(m.axes[a]);
    path += d[a] * d[a];
  }
  path = std::sqrt(path);
  if (path == 0) return 0;
  double v = std::numeric_limits<double>::infinity();  // m/s along the path
  for (size_t a = 0; a < axes_of(m); ++a)
    if (d[a] != 0) v = std::min(v, m.axes[a].max_speed_m_s * path / std::fabs(d[a]));
  return v * 60e3;
}

void check_feed(const MachineConfig& m, const Vec3& from, const Vec3& to, double feed, const Asked& asked) {
  const double top = max_feed_mm_min(m, from, to);
  if (top == 0) return;  // nothing moves
  std::string limits;
  for (size_t a = 0; a < axes_of(m); ++a)
    if (to[a] != from[a])
      limits += (limits.empty() ? "" : ", ") + m.axes[a].name + " " + format_number(m.axes[a].max_speed_m_s);
  mc::host::require_in(feed, mc::host::Bounds{0, top, "mm/min"}, asked.option, asked.as_written,
                       "max_speed_m_s of the moving axes: " + limits + " m/s");
}

std::array<uint32_t, 3> ferr_counts(const MachineConfig& m) {
  std::array<uint32_t, 3> c{};
  for (size_t a = 0; a < axes_of(m); ++a) {
    const double n = std::floor(m.axes[a].max_following_error_m * counts_per_m(m.axes[a]));
    c[a] = uint32_t(std::clamp(n, 1.0, double(kFerrMax)));
  }
  return c;
}

void arm_following_limits(mc::host::BoardLink& l, const MachineConfig& m) {
  namespace br = mc::board::reg;
  const std::array<uint32_t, 3> c = ferr_counts(m);
  const int naxes = mc::host::read_naxes(l);
  for (int a = 0; a < naxes && a < int(axes_of(m)); ++a) {
    // A stepper axis holds its position whenever armed: FOLLOW is the steps
    // owed (open loop) or the steps lost (closed loop).
    const bool held =
        m.axes[size_t(a)].stepper || (l.read(mc::pid_reg::addr(uint8_t(a), mc::pid_reg::CTRL)) & 1);
    const uint32_t want = held ? c[size_t(a)] : 0;
    const uint16_t addr = br::axis(a, br::AX_FERR);
    if ((l.read(addr) & kFerrMax) != want) l.write_verify(addr, want, kFerrMax);
  }
}

int64_t counts_of(double mm, double counts_per_m) {
  constexpr double kFar = 9007199254740992.0;  // 2^53
  return std::llround(std::clamp(mm * 1e-3 * counts_per_m, -kFar, kFar));
}

uint32_t step_ferr_counts(const MachineConfig& m, int axis, int64_t step_counts, const Asked& asked) {
  const uint32_t margin = ferr_counts(m).at(size_t(axis));
  const int64_t need = std::llabs(step_counts) + margin;
  if (need <= kFerrMax) return uint32_t(need);
  const double cpm = counts_per_m(m.axes.at(size_t(axis)));
  throw InputError(std::string(asked.option), value_of(asked, mm(double(step_counts) / cpm)),
                   "a step of at most " + mm(double(kFerrMax - margin) / cpm) +
                       " (the step plus max_following_error_m must fit the board's 16-bit FERR: " +
                       std::to_string(kFerrMax) + " counts)");
}

}  // namespace mc::machine
