// motionctl gcode check|path|plot: a G-code program without a board.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/gcode/interpreter.hpp"
#include "host/machine/job.hpp"

namespace mc::host::cli {
namespace {

struct GcodeOptions {
  std::string file, start = "0,0,0", out, level;
  bool csv = false;
};

std::optional<mc::machine::HeightMap> height_map(const GcodeOptions& o) {
  if (o.level.empty()) return std::nullopt;
  return mc::machine::load_height_map(o.level);
}

mc::machine::Job plan(const GcodeOptions& o, const mc::machine::MachineConfig& m, const Vec3d& start) {
  const std::optional<mc::machine::HeightMap> level = height_map(o);
  return mc::machine::plan_job(o.file, m, start, level ? &*level : nullptr);
}

Vec3d parse_start(const std::string& text) {
  Vec3d p{};
  std::stringstream ss(text);
  size_t n = 0;
  for (std::string part; std::getline(ss, part, ',');) {
    if (n == 3) break;
    p[n++] = parse_number(part, "--start");
  }
  if (n != 3) throw InputError("--start", quote(text), "X,Y,Z in mm (machine coordinates)");
  return p;
}

mc::gcode::ProgramResult interpret(const std::string& file, const Vec3d& start) {
  mc::gcode::Options o;
  o.start = start;
  mc::gcode::ProgramResult r = mc::gcode::interpret_file(file, o);
  if (!r.ok()) throw mc::machine::ProgramErrors(r.errors);
  return r;
}

std::string mm(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4f", v);
  return b;
}

void check(const GcodeOptions& o) {
  const auto m = machine();
  const Vec3d start = parse_start(o.start);
  const mc::machine::Job j = plan(o, m, start);
  const PlanSummary& s = j.summary;
  std::printf("%s: OK, %d lines\n", o.file.c_str(), j.lines);
  if (!o.level.empty()) std::printf("  levelled by %s\n", o.level.c_str());
  std::printf("  moves: %d (%d arcs), %d dwells, %d stops for spindle/coolant/tool/program words\n", s.moves,
              s.arcs, s.dwells, s.actions);
  std::printf("  path: %.3f mm cutting, %.3f mm rapid; %zu board segments\n", s.length_mm, s.rapid_mm,
              s.pieces);
  std::printf("  planned time: %s\n", format_duration(s.time_s).c_str());
  std::printf("  reach (machine mm) against the travel of %s:\n", m.source.c_str());
  for (size_t k = 0; k < 3; ++k) {
    if (!j.cfg.axes[k].present) continue;
    std::printf("    %c %10.3f .. %-10.3f  travel %.1f .. %.1f\n", "XYZ"[k], s.moves ? s.min[k] : start[k],
                s.moves ? s.max[k] : start[k], j.cfg.axes[k].min_mm, j.cfg.axes[k].max_mm);
  }
  std::printf("  peak acceleration of the command (%.0f ms average):", j.cfg.accel_window_s * 1e3);
  for (size_t k = 0; k < 3; ++k)
    if (j.cfg.axes[k].present)
      std::printf(" %c %.0f/%.0f", "XYZ"[k], s.peak_accel[k], j.cfg.axes[k].max_accel_mm_s2);
  std::printf(" mm/s^2\n");
}

void path(const GcodeOptions& o) {
  const Vec3d start = parse_start(o.start);
  const std::optional<mc::machine::HeightMap> level = height_map(o);
  mc::gcode::ProgramResult r = interpret(o.file, start);
  if (level) {
    const double tol = mc::machine::planner_config(machine()).arc_tolerance_mm;
    r.calls = mc::machine::level_calls(r.calls, start, *level, mc::machine::LevelOptions{tol}, o.file);
  }
  std::printf("kind,x,y,z,feed_mm_min,cx,cy,cz,dir,plane\n");
  Vec3d at = start;
  for (const mc::gcode::CanonCall& c : r.calls) {
    std::visit(
        [&](const auto& op) {
          using T = std::decay_t<decltype(op)>;
          auto row = [](const char* kind, const Vec3d& p, const std::string& feed, const std::string& rest) {
            std::printf("%s,%s,%s,%s,%s,%s\n", kind, mm(p[0]).c_str(), mm(p[1]).c_str(), mm(p[2]).c_str(),
                        feed.c_str(), rest.c_str());
          };
          if constexpr (std::is_same_v<T, mc::gcode::StraightTraverse>) {
            row("rapid", op.end, "", ",,,,");
            at = op.end;
          } else if constexpr (std::is_same_v<T, mc::gcode::StraightFeed>) {
            row("feed", op.end, mm(op.feed_mm_min), ",,,,");
            at = op.end;
          } else if constexpr (std::is_same_v<T, mc::gcode::StraightProbe>) {
            row("probe", op.end, mm(op.feed_mm_min), ",,,,");
            at = op.end;
          } else if constexpr (std::is_same_v<T, mc::gcode::ArcFeed>) {
            const char* plane = op.plane == mc::gcode::Plane::xy   ? "17"
                                : op.plane == mc::gcode::Plane::xz ? "18"
                                                                   : "19";
            row("arc", op.end, mm(op.feed_mm_min),
                mm(op.centre[0]) + "," + mm(op.centre[1]) + "," + mm(op.centre[2]) + "," +
                    (op.clockwise ? "cw" : "ccw") + "," + plane);
            at = op.end;
          } else if constexpr (std::is_same_v<T, mc::gcode::Dwell>) {
            row("dwell", at, "", ",,,,");
          }
        },
        c.op);
  }
}

void plot(const GcodeOptions& o) {
  if (o.out.empty()) throw InputError("-o", "(none)", "an output file, e.g. -o path.png");
  require_writable_file(o.out, "-o");
  const auto m = machine();
  const Vec3d start = parse_start(o.start);
  const mc::machine::Job j = plan(o, m, start);
  plot_xy(o.out, o.file + ": tool path (machine mm), rapids dashed",
          {{"feed", moves_xy(j.moves, false), "lines lw 1.5 lc rgb '#1f77b4'"},
           {"rapid", moves_xy(j.moves, true), "lines dt 2 lc rgb '#d62728'"}});
  std::printf("wrote %s (%d moves)\n", o.out.c_str(), j.summary.moves);
}

}  // namespace

void add_gcode_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("gcode", "Check, list or plot a G-code program (no board)");
  cmd->require_subcommand(1);
  auto add = [&](const char* name, const char* help) {
    auto o = std::make_shared<GcodeOptions>();
    CLI::App* s = cmd->add_subcommand(name, help);
    s->add_option("file", o->file, "G-code program")->required()->type_name("FILE");
    s->add_option("--start", o->start, "where the machine stands, X,Y,Z machine mm (default 0,0,0)")
        ->type_name("X,Y,Z");
    s->add_option("--level", o->level, "Apply a bed height map (docs/levelling.md), as run --level does")
        ->type_name("MAP");
    return std::make_pair(s, o);
  };
  auto [c, co] = add("check", "Errors (FILE:LINE:COLUMN, exit 2), or a summary: moves, reach, planned time");
  c->footer("Plans the program with the machine's limits (--config): travel, rates, accelerations.");
  c->callback([co = co] { check(*co); });
  auto [p, po] =
      add("path", "One CSV row per motion in machine mm: kind,x,y,z,feed_mm_min,cx,cy,cz,dir,plane");
  p->add_flag("--csv", po->csv, "CSV on stdout (the only format)");
  p->callback([po = po] { path(*po); });
  auto [l, lo] = add("plot", "The tool path as a PNG, rapids dashed (needs gnuplot)");
  l->add_option("-o,--out", lo->out, "PNG file to write")->required()->type_name("FILE");
  l->callback([lo = lo] { plot(*lo); });
}

}  // namespace mc::host::cli
