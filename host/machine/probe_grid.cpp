#include "host/machine/probe_grid.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "host/base/errors.hpp"
#include "host/machine/cycles.hpp"
#include "host/machine/job.hpp"
#include "host/machine/limits.hpp"

namespace mc::machine {

using mc::host::format_number;
using mc::host::InputError;
using mc::host::Vec3;

void check_probe_grid(const ProbeGridOptions& o) {
  if (o.nx < 2 || o.ny < 2 || o.nx > 100 || o.ny > 100)
    throw InputError("--grid", std::to_string(o.nx) + "x" + std::to_string(o.ny), "NxM points, each 2..100");
  if (!(o.x1 > o.x0) || !(o.y1 > o.y0) || !std::isfinite(o.x1 - o.x0) || !std::isfinite(o.y1 - o.y0))
    throw InputError("--area",
                     format_number(o.x0) + "," + format_number(o.y0) + "," + format_number(o.x1) + "," +
                         format_number(o.y1),
                     "X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1 (machine mm)");
  for (const auto& [what, v] :
       {std::pair{"--feed", o.feed_mm_min}, std::pair{"--travel-feed", o.travel_mm_min},
        std::pair{"--clearance", o.clearance_mm}, std::pair{"--distance", o.depth_mm}})
    if (!(v > 0) || !std::isfinite(v)) throw InputError(what, format_number(v), "above 0");
}

ProbedGrid probe_grid(mc::host::BoardLink& l, const MachineConfig& m, const ProbeGridOptions& o,
                      const mc::host::Note& note, const std::function<void(int, int)>& progress) {
  check_probe_grid(o);
  if (m.axes.size() < 3) throw InputError("machine config", m.source, "a Z axis to probe with", "no axis z");
  // Every point and depth inside the travel before anything changes on the
  // board (in the machine frame: the origin taken off).
  const mc::host::MachineOrigin org = mc::host::read_origin(l);
  const mc::host::PlannerConfig cfg = planner_config(m, org.counts);
  const Vec3 start_counts = mc::host::start_position(l);
  const mc::host::Vec3d start = mc::host::to_mm(start_counts, cfg);
  const double bottom = start[2] - o.depth_mm;
  const auto counts = [&](double x, double y, double z) { return mc::host::to_counts({x, y, z}, cfg); };
  const mc::host::Vec3d corners[] = {{o.x0, o.y0, bottom},
                                     {o.x1, o.y1, bottom},
                                     {o.x0, o.y1, start[2]},
                                     {o.x1, o.y0, start[2] + o.clearance_mm}};
  for (const mc::host::Vec3d& c : corners)
    check_travel(m, org.machine(start_counts), org.machine(counts(c[0], c[1], c[2])),
                 {"--area/--distance",
                  format_number(c[0]) + "," + format_number(c[1]) + " at Z" + format_number(c[2])});
  const JobBoard jb = ready_board(l, m, note);

  ProbedGrid g;
  g.map.nx = o.nx;
  g.map.ny = o.ny;
  g.map.x0 = o.x0;
  g.map.y0 = o.y0;
  g.map.dx = (o.x1 - o.x0) / (o.nx - 1);
  g.map.dy = (o.y1 - o.y0) / (o.ny - 1);
  g.map.z.assign(size_t(o.nx) * size_t(o.ny), 0);
  Vec3 at = jb.at;
  const auto move = [&](const Vec3& to, double feed_mm_min) {
    LatchedMove mv(
        l, {at, to, path_feed_counts_s(at, to, feed_mm_min, cfg), LatchedMove::Source::none, 0, false});
    while (!mv.poll()) wait_on_link(l);
    at = mv.end();
  };
  // Straight up from where the tool stands.
  const auto rise = [&](double z) {
    const mc::host::Vec3d p = mc::host::to_mm(at, cfg);
    move(counts(p[0], p[1], z), o.travel_mm_min);
  };
  double highest = -1e300;
  int done = 0;
  if (progress) progress(0, o.nx * o.ny);
  for (int j = 0; j < o.ny; ++j)
    for (int n = 0; n < o.nx; ++n) {
      // Back and forth along X: no move crosses the whole area empty.
      const int i = j % 2 == 0 ? n : o.nx - 1 - n;
      const double x = o.x0 + i * g.map.dx, y = o.y0 + j * g.map.dy;
      const double travel_z = done == 0 ? start[2] : highest + o.clearance_mm;
      if (done > 0) rise(travel_z);
      move(counts(x, y, travel_z), o.travel_mm_min);
      const Vec3 down = counts(x, y, bottom);
      std::optional<ProbeCycle> pc;
      try {
        pc.emplace(l, at, down, path_feed_counts_s(at, down, o.feed_mm_min, cfg), true, 7);
      } catch (const CycleError& e) {
        throw CycleError(e.grbl_alarm(), std::string(e.what()) + " at X" + format_number(x) + " Y" +
                                             format_number(y) +
                                             (done == 0 ? ": start with the tool above the work" : ""));
      }
      ProbeCycle& c = *pc;
      while (!c.poll()) wait_on_link(l);
      at = c.end();
      if (!c.contact())
        throw CycleError(5, "probe: no contact at X" + format_number(x) + " Y" + format_number(y) +
                                " within " + format_number(o.depth_mm) + " mm below the start");
      const double z = mc::host::to_mm(c.position(), cfg)[2];
      if (done == 0) g.z0_mm = z;
      g.map.z[size_t(j) * size_t(o.nx) + size_t(i)] = z - g.z0_mm;
      highest = std::max(highest, z);
      ++done;
      if (progress) progress(done, o.nx * o.ny);
    }
  rise(highest + o.clearance_mm);  // clear of the work at the end, as between points
  return g;
}

}  // namespace mc::machine
