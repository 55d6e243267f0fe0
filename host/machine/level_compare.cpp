#include "host/machine/level_compare.hpp"

#include "host/base/errors.hpp"
#include "host/machine/job.hpp"
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
  c.program = engraving_program(w, c.map, o.depth_mm, o.feed_mm_min, o.rows, o.columns);
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
