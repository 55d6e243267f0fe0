// motionctl run FILE: a G-code job on the board or the virtual board, with a
// progress bar, and a report of how well the machine followed the program.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/link/board_capture.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/job.hpp"
#include "host/machine/spindle.hpp"

namespace mc::host::cli {
namespace {

struct RunOptions {
  std::string file, plot, csv, level;
  bool json = false, quiet = false;
};

std::string action_text(const Move& m) {
  return std::visit(
      [](const auto& op) -> std::string {
        using T = std::decay_t<decltype(op)>;
        char b[120];
        if constexpr (std::is_same_v<T, mc::gcode::StartSpindle>) {
          std::snprintf(b, sizeof b, "spindle on, %s, %.0f rpm",
                        op.clockwise ? "clockwise" : "counter-clockwise", op.rpm);
          return b;
        } else if constexpr (std::is_same_v<T, mc::gcode::SetSpindleSpeed>) {
          std::snprintf(b, sizeof b, "spindle speed %.0f rpm", op.rpm);
          return b;
        } else if constexpr (std::is_same_v<T, mc::gcode::StopSpindle>) {
          return "spindle off";
        } else if constexpr (std::is_same_v<T, mc::gcode::SetCoolant>) {
          return std::string("coolant: mist ") + (op.mist ? "on" : "off") + ", flood " +
                 (op.flood ? "on" : "off");
        } else if constexpr (std::is_same_v<T, mc::gcode::ChangeTool>) {
          return "tool change to T" + std::to_string(op.tool);
        } else if constexpr (std::is_same_v<T, mc::gcode::ProgramStop>) {
          return op.kind == mc::gcode::StopKind::pause            ? "program pause (M0)"
                 : op.kind == mc::gcode::StopKind::optional_pause ? "optional pause (M1)"
                                                                  : "program end";
        } else {
          return "stop";
        }
      },
      *m.action);
}

bool pauses(const Move& m) {
  if (const auto* s = std::get_if<mc::gcode::ProgramStop>(&*m.action))
    return s->kind == mc::gcode::StopKind::pause || s->kind == mc::gcode::StopKind::optional_pause;
  return std::holds_alternative<mc::gcode::ChangeTool>(*m.action);
}

// The progress line on a terminal: a bar, the line being run, the ETA from
// the plan.
class Progress {
 public:
  Progress(const mc::machine::Job& j, bool on) : j_(j), on_(on && ::isatty(STDERR_FILENO)) {}
  void show(double t, int line) {
    if (!on_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double total = j_.summary.time_s;
    const double f = total > 0 ? t / total : 1;
    const int width = 30, filled = int(f * width);
    std::fprintf(stderr, "\r[%s%s] %3.0f%%  line %-6d  ETA %-8s", std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(width - filled), '.').c_str(), 100 * f, line,
                 format_duration(std::max(0.0, total - t)).c_str());
    std::fflush(stderr);
    shown_ = true;
  }
  void clear() {
    if (shown_) std::fprintf(stderr, "\r%60s\r", "");
    shown_ = false;
  }

 private:
  const mc::machine::Job& j_;
  bool on_, shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

void plot_run(const std::string& out, const mc::machine::Job& j, const StreamResult& r) {
  std::ostringstream meas;
  for (const JobSample& s : r.samples) {
    const Vec3d p = to_mm(Vec3{s.pos[0], s.pos[1], s.pos[2]}, j.cfg);
    meas << p[0] << ' ' << p[1] << '\n';
  }
  plot_xy(out, j.file + ": programmed and measured path (machine mm)",
          {{"programmed", moves_xy(j.moves, false) + "\n" + moves_xy(j.moves, true),
            "lines lw 2 lc rgb '#999999'"},
           {"measured (telemetry)", meas.str(), "lines lw 1 lc rgb '#d62728'"}});
}

void run_job(const RunOptions& o) {
  const auto m = machine();
  // Every G-code error before the board is touched (the machine's limits
  // are checked once the start is known, still before anything moves).
  const mc::gcode::ProgramResult checked = mc::gcode::interpret_file(o.file);
  if (!checked.ok()) throw mc::machine::ProgramErrors(checked.errors);
  std::optional<mc::machine::HeightMap> level;
  if (!o.level.empty()) level = mc::machine::load_height_map(o.level);
  for (const auto& [opt, path] : {std::pair{"--plot", o.plot}, std::pair{"--csv", o.csv}})
    if (!path.empty()) require_writable_file(path, opt);
  Board b = open_board();
  BoardLink& l = *b.link;
  const mc::machine::JobBoard jb = mc::machine::ready_board(l, m, note);
  const std::vector<int>& axes = jb.axes;
  const Vec3 at = jb.at;
  const mc::host::PlannerConfig cfg = mc::machine::planner_config(m, jb.origin);
  const mc::machine::Job j =
      mc::machine::plan_job(o.file, m, to_mm(at, cfg), level ? &*level : nullptr, jb.origin);
  // Ctrl-C from here on stops the job along the path; the line below says so.
  catch_interrupts();
  if (!o.json) {
    std::printf("running %s%s: %d moves, %zu segments, planned %s on %s (Ctrl-C stops)\n", o.file.c_str(),
                level ? (" levelled by " + o.level).c_str() : "", j.summary.moves, j.pieces.size(),
                format_duration(j.summary.time_s).c_str(), b.where.c_str());
    std::fflush(stdout);
  }
  // The spindle and coolant start off and follow the program's M3/M4/M5,
  // S, M7/M8/M9 (IO_CTRL), whatever a previous run left.
  mc::machine::SpindleState spindle;
  mc::machine::write_spindle(l, m, spindle);
  Progress bar(j, !o.quiet && !o.json);
  StreamOptions so;
  so.queue_ahead_s = m.planner.queue_ahead_s;
  for (int a : axes) so.telemetry_axes |= 1u << a;
  so.ts_s = jb.ts_s;
  so.stop = &interrupt_requested();
  so.progress = [&](double t, int line) { bar.show(t, line); };
  so.action = [&](const Move& mv) {
    bar.clear();
    spindle.apply(*mv.action);
    mc::machine::write_spindle(l, m, spindle);
    if (o.json) return;
    std::printf("line %d: %s\n", mv.line, action_text(mv).c_str());
    if (pauses(mv) && ::isatty(STDIN_FILENO)) {
      std::printf("  paused: press Enter to continue\n");
      std::string line;
      std::getline(std::cin, line);
    }
  };
  const StreamResult r = stream_job(l, j.moves, j.pieces, cfg, so);
  bar.clear();
  // Drives off stops the spindle too; the next arm clears IO_CTRL.
  if (r.stopped) disable_axes(l, axes, true);
  const mc::machine::JobReport rep = mc::machine::report(j, r, jb.ts_s);
  if (!o.plot.empty()) plot_run(o.plot, j, r);
  if (!o.csv.empty()) {
    std::ofstream f(o.csv);
    f << "t_s,cmd_x_mm,cmd_y_mm,cmd_z_mm,pos_x_mm,pos_y_mm,pos_z_mm\n";
    for (const JobSample& x : r.samples) {
      const Vec3d c = to_mm(Vec3{x.cmd[0], x.cmd[1], x.cmd[2]}, cfg),
                  p = to_mm(Vec3{x.pos[0], x.pos[1], x.pos[2]}, cfg);
      f << double(x.n - r.samples.front().n) * jb.ts_s << ',' << c[0] << ',' << c[1] << ',' << c[2] << ','
        << p[0] << ',' << p[1] << ',' << p[2] << '\n';
    }
  }
  if (o.json) {
    nlohmann::ordered_json js;
    js["file"] = o.file;
    js["stopped"] = rep.stopped;
    js["planned_s"] = rep.planned_s;
    js["board_s"] = rep.board_s;
    js["underruns"] = rep.underruns;
    js["segments"] = rep.segments;
    js["segments_per_s"] = rep.segments_per_s;
    js["peak_accel_mm_s2"] = rep.peak_accel;
    js["accel_limit_mm_s2"] = rep.accel_limit;
    js["contour_rms_um"] = rep.contour.rms * 1e3;
    js["contour_max_um"] = rep.contour.max * 1e3;
    js["following_rms_um"] = rep.following.rms * 1e3;
    js["following_max_um"] = rep.following.max * 1e3;
    js["samples"] = rep.contour.n;
    js["telemetry_gaps"] = rep.telemetry_gaps;
    std::cout << js.dump(2) << '\n';
  } else {
    if (rep.stopped)
      std::printf("stopped on request at line %d: decelerated along the path, drives off\n",
                  rep.stopped_at_line);
    else
      std::printf("done: %s\n", o.file.c_str());
    const double dt = rep.planned_s > 0 ? 100 * (rep.board_s / rep.planned_s - 1) : 0;
    std::printf("  time: %s on the board, planned %s (%+.2f %%)\n", format_duration(rep.board_s).c_str(),
                format_duration(rep.planned_s).c_str(), dt);
    std::printf("  underruns: %d; %zu segments, %.0f segments/s\n", rep.underruns, rep.segments,
                rep.segments_per_s);
    std::printf("  peak acceleration of the command (%.0f ms average):", cfg.accel_window_s * 1e3);
    for (size_t k = 0; k < 3; ++k)
      if (cfg.axes[k].present)
        std::printf(" %c %.0f of %.0f", "XYZ"[k], rep.peak_accel[k], rep.accel_limit[k]);
    std::printf(" mm/s^2\n");
    std::printf(
        "  contour error (measured to programmed path, cutting moves): RMS %.2f um, max %.2f um, %zu "
        "samples%s\n",
        rep.contour.rms * 1e3, rep.contour.max * 1e3, rep.contour.n,
        rep.telemetry_gaps ? (" (" + std::to_string(rep.telemetry_gaps) + " telemetry gaps)").c_str() : "");
    std::printf("  following error (worst axis): RMS %.2f um, max %.2f um\n", rep.following.rms * 1e3,
                rep.following.max * 1e3);
    if (!o.plot.empty()) std::printf("  wrote %s\n", o.plot.c_str());
  }
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "Run a G-code job: streams it, then reports time, acceleration, errors");
  cmd->footer(std::string(kBoardFooter) +
              "\nThe whole program is checked first: an error anywhere moves nothing. Enables every axis of\n"
              "the machine config and plans from where the axes stand (machine mm = counts / scale). Ctrl-C\n"
              "decelerates along the path at the acceleration limit, stops and turns the drives off.\n"
              "M0, M1 and M6 wait for Enter when stdin is a terminal.");
  cmd->add_option("file", o->file, "G-code program")->required()->type_name("FILE");
  cmd->add_option("--plot", o->plot, "PNG of the programmed and the measured path (needs gnuplot)")
      ->type_name("FILE");
  cmd->add_option("--csv", o->csv, "The telemetry samples: time, command and position per axis, mm")
      ->type_name("FILE");
  cmd->add_option("--level", o->level,
                  "Follow the bed: a height map (docs/levelling.md) added to every Z, moves split per cell")
      ->type_name("MAP");
  cmd->add_flag("--json", o->json, "The report as one JSON object");
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  cmd->callback([o] { run_job(*o); });
}

}  // namespace mc::host::cli
