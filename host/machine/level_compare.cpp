#include "host/machine/level_compare.hpp"

#include <algorithm>
#include "host/base/errors.hpp"

#include "host/machine/cycles.hpp"
#include "host/machine/job.hpp"
#include "host/machine/probe_grid.hpp"
#include "host/motion/job_stream.hpp"

namespace mc::machine {

LevelComparison compare_levelling(mc::host::BoardLink& l, const MachineConfig& m,
                                  const LevelCompareOptions& o, const mc::host::Note& note) {
  if (!m.workpiece)
    throw mc::host::InputError("machine config", m.source, "a [workpiece] table",
                               "the machine has no workpiece");
  if (m.axes.size() < 3) throw mc::host::InputError("machine config", m.source, "a Z axis", "no axis z");
  if (!(o.depth_mm > 0) || o.depth_mm > 5)
    throw mc::host::InputError("--depth", mc::host::format_number(o.depth_mm), "0 < depth <= 5 mm");
  const WorkpieceConfig& w = *m.workpiece;
  LevelComparison c;
  c.map = sample_height_map(w, o.nx, o.ny, o.inset_mm);
  c.work_zero_z_mm = surface_z_mm(w, c.map.x0, c.map.y0);
  if (o.probe) {
    // From above the first point, clear of the face's highest point.
    note("probing the map: " + std::to_string(o.nx) + " x " + std::to_string(o.ny) + " points");
    double top = -1e300;
    for (double z : c.map.z) top = std::max(top, z + c.work_zero_z_mm);
    const JobBoard jb = ready_board(l, m, note);
    const mc::host::PlannerConfig cfg = planner_config(m, jb.origin);
    const mc::host::Vec3 above = mc::host::to_counts({c.map.x0, c.map.y0, top + 3}, cfg);
    LatchedMove mv(
        l, {jb.at, above, path_feed_counts_s(jb.at, above, 1500, cfg), LatchedMove::Source::none, 0, false});
    while (!mv.poll()) wait_on_link(l);
    ProbeGridOptions po;
    po.nx = o.nx;
    po.ny = o.ny;
    po.x0 = c.map.x0;
    po.y0 = c.map.y0;
    po.x1 = c.map.x1();
    po.y1 = c.map.y1();
    const ProbedGrid g = probe_grid(l, m, po, note);
    c.map = g.map;
    c.work_zero_z_mm = g.z0_mm;  // where the operator's touch-off would put it
  }
  c.program = engraving_program(c.map, c.work_zero_z_mm, o.depth_mm, o.feed_mm_min, o.rows, o.columns);
  struct Variant {
    const char* name;
    const HeightMap* map;
    LevelMethod method;
  };
  const Variant variants[] = {{"none", nullptr, LevelMethod::bilinear},
                              {"end points (paper)", &c.map, LevelMethod::end_points},
                              {"bilinear, split per cell", &c.map, LevelMethod::bilinear}};
  for (const Variant& v : variants) {
    note(std::string("engraving, levelling: ") + v.name);
    const JobBoard jb = ready_board(l, m, note);
    const mc::host::PlannerConfig cfg = planner_config(m, jb.origin);
    const Job j =
        plan_program(c.program, "engraving", m, mc::host::to_mm(jb.at, cfg), v.map, v.method, jb.origin);
    mc::host::StreamOptions so;
    so.queue_ahead_s = m.planner.queue_ahead_s;
    for (int a : jb.axes) so.telemetry_axes |= 1u << a;
    so.ts_s = jb.ts_s;
    const mc::host::StreamResult r = mc::host::stream_job(l, j.moves, j.pieces, cfg, so);
    LevelCompareRun run;
    run.method = v.name;
    run.depth = depth_error(r.samples, cfg, w, c.map, o.depth_mm);
    run.planned_s = r.planned_s;
    run.underruns = r.underruns;
    c.runs.push_back(run);
  }
  return c;
}

}  // namespace mc::machine
