// motionctl level compare: the levelling comparison of docs/levelling.md on
// the virtual board.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "host/machine/level_compare.hpp"

namespace mc::host::cli {
namespace {

struct CompareOptions {
  mc::machine::LevelCompareOptions c;
  std::string grid = "9x7", map_out, program_out;
};

void parse_grid(const std::string& text, int& nx, int& ny) {
  const size_t x = text.find('x');
  int a = 0, b = 0;
  char tail = 0;
  if (x == std::string::npos || std::sscanf(text.c_str(), "%dx%d%c", &a, &b, &tail) != 2 || a < 2 || b < 2 ||
      a > 100 || b > 100)
    throw InputError("--grid", quote(text), "NxM points, each 2..100, e.g. 9x7");
  nx = a;
  ny = b;
}

void compare(CompareOptions o) {
  if (!global_options().sim)
    throw InputError("level compare", global_options().port.empty() ? "(no board)" : "--port",
                     "--sim: it measures against the machine TOML's [workpiece], the virtual board's plant");
  parse_grid(o.grid, o.c.nx, o.c.ny);
  if (!o.map_out.empty()) require_writable_file(o.map_out, "--map");
  if (!o.program_out.empty()) require_writable_file(o.program_out, "--program");
  const auto m = machine();
  Board b = open_board();
  const mc::machine::LevelComparison r = mc::machine::compare_levelling(*b.link, m, o.c, note);
  if (!o.map_out.empty()) std::ofstream(o.map_out) << mc::machine::format_height_map(r.map);
  if (!o.program_out.empty()) std::ofstream(o.program_out) << r.program;
  const mc::machine::WorkpieceConfig& w = *m.workpiece;
  std::printf(
      "levelling on the virtual workpiece of %s (%.0f x %.0f mm, tilt %.3f mm/100 mm in X, dish %.3f mm, "
      "roughness %.1f um RMS)\n",
      m.source.c_str(), (w.max_x_m - w.min_x_m) * 1e3, (w.max_y_m - w.min_y_m) * 1e3, w.tilt_x * 100,
      w.bow_m * 1e3, w.noise_m * 1e6);
  std::printf(
      "engraving %.3f mm deep: %d cuts along X, %d along Y at %.0f mm/min; map %d x %d points, %.1f x %.1f "
      "mm "
      "apart (a perfect probe's)\n",
      o.c.depth_mm, o.c.rows, o.c.columns, o.c.feed_mm_min, r.map.nx, r.map.ny, r.map.dx, r.map.dy);
  std::printf("depth error: measured Z - (face - depth) along the cuts, um (+ too shallow)\n");
  std::printf("%-26s %9s %9s %10s %12s %8s %10s\n", "levelling", "RMS", "max |e|", "deepest", "shallowest",
              "samples", "underruns");
  for (const mc::machine::LevelCompareRun& x : r.runs)
    std::printf("%-26s %9.1f %9.1f %10.1f %12.1f %8zu %10d\n", x.method.c_str(), x.depth.rms_mm * 1e3,
                x.depth.max_mm * 1e3, x.depth.min_mm * 1e3, x.depth.worst_mm * 1e3, x.depth.n, x.underruns);
}

}  // namespace

void add_level_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("level", "Bed levelling: compare methods on the virtual workpiece");
  cmd->require_subcommand(1);
  auto o = std::make_shared<CompareOptions>();
  CLI::App* c = cmd->add_subcommand(
      "compare", "Engrave the virtual workpiece without levelling, with the paper's method and with a map");
  c->footer(
      "Needs --sim: the depth is measured against the machine TOML's [workpiece] (the virtual board's\n"
      "plant). The map is what a perfect probe would take of that face at the grid's points.");
  c->add_option("--grid", o->grid, "Map points NxM over the workpiece (default 9x7)")->type_name("NxM");
  c->add_option("--depth", o->c.depth_mm, "Engraving depth, mm (default 0.1)")->type_name("MM");
  c->add_option("--feed", o->c.feed_mm_min, "Cutting feed, mm/min (default 1500)")->type_name("MM/MIN");
  c->add_option("--rows", o->c.rows, "Cuts along X (default 3)")->check(CLI::Range(1, 50));
  c->add_option("--columns", o->c.columns, "Cuts along Y (default 2)")->check(CLI::Range(0, 50));
  c->add_option("--map", o->map_out, "Also write the map (TOML, docs/levelling.md)")->type_name("FILE");
  c->add_option("--program", o->program_out, "Also write the engraving (G-code)")->type_name("FILE");
  c->callback([o] { compare(*o); });
}

}  // namespace mc::host::cli
