#include "host/machine/job.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "host/base/errors.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/gains_file.hpp"
#include "host/machine/limits.hpp"

namespace mc::machine {

using mc::host::InputError;
using mc::host::Move;
using mc::host::Vec3d;

mc::host::PlannerConfig planner_config(const MachineConfig& m, const mc::host::Vec3& origin) {
  mc::host::PlannerConfig c;
  for (size_t k = 0; k < m.axes.size() && k < 3; ++k) {
    const AxisConfig& a = m.axes[k];
    mc::host::AxisLimits& l = c.axes[k];
    l.present = true;
    l.counts_per_mm = counts_per_m(a) * 1e-3;
    l.max_rate_mm_s = a.max_speed_m_s * 1e3;
    l.max_accel_mm_s2 = a.max_accel_m_s2 * 1e3;
    l.min_mm = a.travel_min_m * 1e3;
    l.max_mm = a.travel_max_m * 1e3;
    l.origin = origin[k];
  }
  c.junction_deviation_mm = m.planner.junction_deviation_m * 1e3;
  c.arc_tolerance_mm = m.planner.arc_tolerance_m * 1e3;
  c.ramp_piece_s = m.planner.ramp_piece_s;
  c.accel_window_s = m.planner.accel_window_s;
  c.clock_hz = m.clock_hz;
  return c;
}

namespace {
std::string list(const std::vector<mc::gcode::Error>& errors) {
  std::string s;
  for (const auto& e : errors) s += (s.empty() ? "" : "\n") + e.format();
  return s;
}
}  // namespace

ProgramErrors::ProgramErrors(std::vector<mc::gcode::Error> errors)
    : std::runtime_error(list(errors)), errors_(std::move(errors)) {}

Job plan_program(std::string_view text, const std::string& name, const MachineConfig& m, const Vec3d& start,
                 const HeightMap* level, LevelMethod method, const mc::host::Vec3& origin) {
  mc::gcode::Options o;
  o.start = start;
  const mc::gcode::ProgramResult prog = mc::gcode::interpret_program(text, name, o);
  if (!prog.ok()) throw ProgramErrors(prog.errors);
  Job j;
  j.file = name;
  j.cfg = planner_config(m, origin);
  j.lines = prog.lines;
  std::vector<mc::gcode::CanonCall> calls = prog.calls;
  if (level) {
    const LevelOptions lo{j.cfg.arc_tolerance_mm};
    calls = method == LevelMethod::bilinear ? level_calls(prog.calls, start, *level, lo, name)
                                            : level_calls_endpoints(prog.calls, start, *level, lo, name);
  }
  j.moves = mc::host::to_moves(calls, start, j.cfg, name);
  mc::host::plan_speeds(j.moves, j.cfg);
  j.pieces = mc::host::chop(j.moves, j.cfg);
  j.summary = mc::host::summarize(j.moves, j.pieces, j.cfg);
  return j;
}

Job plan_job(const std::string& path, const MachineConfig& m, const Vec3d& start, const HeightMap* level,
             const mc::host::Vec3& origin) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("G-code file", mc::host::quote(path), "a readable file", "cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return plan_program(text.str(), path, m, start, level, LevelMethod::bilinear, origin);
}

JobBoard ready_board(mc::host::BoardLink& l, const MachineConfig& m, const mc::host::Note& note) {
  setup_axes(l, m);  // refuses a board not built for the machine's axes
  mc::host::BoardState st = mc::host::read_state(l);
  JobBoard b;
  for (int a = 0; a < int(m.axes.size()) && a < st.naxes; ++a) b.axes.push_back(a);
  if (b.axes.size() < m.axes.size())
    throw InputError("machine config", m.source, "a board with " + std::to_string(m.axes.size()) + " axes",
                     "the board has " + std::to_string(st.naxes));
  // A fresh board (the virtual one after start) has no gains: the machine's.
  if (gains_where_missing(l, m, note) > 0) st = mc::host::read_state(l);
  b.ts_s = st.ts_s();
  // Enabling starts the command where the axes are.
  b.at = enable_machine_axes(l, m, b.axes, note);
  arm_following_limits(l, m);  // a runaway trips FERR instead of running on
  b.origin = mc::host::read_origin(l).counts;
  return b;
}

mc::host::ErrorStats contour_error(const std::vector<mc::host::JobSample>& samples,
                                   const std::vector<Move>& moves, const mc::host::PlannerConfig& cfg) {
  std::vector<std::array<int32_t, 3>> cmd;
  std::vector<Vec3d> pos;
  cmd.reserve(samples.size());
  pos.reserve(samples.size());
  for (const mc::host::JobSample& s : samples) {
    cmd.push_back(s.cmd);
    pos.push_back(mc::host::to_mm(mc::host::Vec3{s.pos[0], s.pos[1], s.pos[2]}, cfg));
  }
  return contour_error(cmd, pos, moves, cfg);
}

mc::host::ErrorStats contour_error(const std::vector<std::array<int32_t, 3>>& cmds,
                                   const std::vector<Vec3d>& pos_mm, const std::vector<Move>& moves,
                                   const mc::host::PlannerConfig& cfg, std::vector<double>* each) {
  if (cmds.size() != pos_mm.size())
    throw std::invalid_argument("contour_error: as many positions as commands are needed");
  if (each) each->assign(cmds.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<size_t> path;  // indices of the motion moves
  for (size_t i = 0; i < moves.size(); ++i)
    if (moves[i].is_motion()) path.push_back(i);
  mc::host::ErrorStats st;
  if (path.empty()) return st;
  double sum2 = 0;
  size_t at = 0;  // the move the command is on; only ever moves forward
  double cell = 0;
  for (const mc::host::AxisLimits& a : cfg.axes)
    if (a.present) cell = std::max(cell, 1.0 / a.counts_per_mm);
  for (size_t i = 0; i < cmds.size(); ++i) {
    const Vec3d cmd = mc::host::to_mm(mc::host::Vec3{cmds[i][0], cmds[i][1], cmds[i][2]}, cfg);
    const Vec3d& pos = pos_mm[i];
    // The move the command is on: the nearest in a window ahead (the
    // command lies on the path to a count or two; at a junction both moves
    // hold it and the later one wins).
    size_t best = at;
    double dbest = std::numeric_limits<double>::infinity();
    for (size_t k = at; k < path.size() && k < at + 64; ++k) {
      const double d = mc::host::distance_to(moves[path[k]], cmd);
      if (d <= dbest + 1e-12) {
        best = k;
        dbest = d;
      }
      if (d > dbest + 100 * cell) break;  // well past it
    }
    if (dbest < 4 * cell) at = best;
    // Rapids are not cutting: how they are followed is the following error's.
    if (moves[path[at]].rapid) continue;
    // The measured point lags the command: look around the command's move.
    double d = std::numeric_limits<double>::infinity();
    const size_t lo = at >= 8 ? at - 8 : 0, hi = std::min(path.size(), at + 9);
    for (size_t k = lo; k < hi; ++k) d = std::min(d, mc::host::distance_to(moves[path[k]], pos));
    if (each) (*each)[i] = d;
    sum2 += d * d;
    st.max = std::max(st.max, d);
    ++st.n;
  }
  st.rms = st.n ? std::sqrt(sum2 / double(st.n)) : 0;
  return st;
}

JobReport report(const Job& job, const mc::host::StreamResult& r, double ts_s) {
  JobReport rep;
  rep.planned_s = r.planned_s;
  rep.underruns = r.underruns;
  rep.segments = r.segments;
  rep.telemetry_gaps = r.gaps;
  rep.stopped = r.stopped;
  rep.stopped_at_line = r.stopped_at_line;
  rep.peak_accel = job.summary.peak_accel;
  for (size_t k = 0; k < 3; ++k) rep.accel_limit[k] = job.cfg.axes[k].max_accel_mm_s2;
  // Board time: from the last sample before the motion began to the first
  // after it ended (the command stands still at both).
  const auto& s = r.samples;
  if (s.size() >= 2) {
    size_t first = 0, last = s.size() - 1;
    while (first + 1 < s.size() && s[first + 1].cmd == s[0].cmd) ++first;
    while (last > first && s[last - 1].cmd == s.back().cmd) --last;
    rep.board_s = double(s[last].n - s[first].n) * ts_s;
    if (rep.board_s > 0) rep.segments_per_s = double(r.segments) / rep.board_s;
  }
  rep.contour = contour_error(s, job.moves, job.cfg);
  double sum2 = 0;
  for (const mc::host::JobSample& x : s) {
    double worst = 0;
    for (size_t k = 0; k < 3; ++k)
      if (job.cfg.axes[k].present)
        worst = std::max(worst, std::fabs(double(x.cmd[k] - x.pos[k])) / job.cfg.axes[k].counts_per_mm);
    sum2 += worst * worst;
    rep.following.max = std::max(rep.following.max, worst);
    ++rep.following.n;
  }
  rep.following.rms = rep.following.n ? std::sqrt(sum2 / double(rep.following.n)) : 0;
  return rep;
}

}  // namespace mc::machine
