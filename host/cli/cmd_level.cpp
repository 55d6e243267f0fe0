// motionctl level probe | compare: probe a bed's height map on the board,
// and the levelling comparison of docs/levelling.md on the virtual board.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/machine/level_compare.hpp"
#include "host/machine/probe_grid.hpp"

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

struct ProbeOptions {
  mc::machine::ProbeGridOptions g;
  std::string grid = "3x3", area, out;
  bool json = false;
};

void parse_area(const std::string& text, mc::machine::ProbeGridOptions& g) {
  double v[4];
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &tail) != 4)
    throw InputError("--area", quote(text), "X0,Y0,X1,Y1 in machine mm, e.g. 5,5,195,145");
  g.x0 = v[0];
  g.y0 = v[1];
  g.x1 = v[2];
  g.y1 = v[3];
}

void probe(ProbeOptions o) {
  parse_grid(o.grid, o.g.nx, o.g.ny);
  parse_area(o.area, o.g);
  require_writable_file(o.out, "-o");
  mc::machine::check_probe_grid(o.g);
  const auto m = machine();
  Board b = open_board();
  const int total = o.g.nx * o.g.ny;
  const mc::machine::ProbedGrid g = mc::machine::probe_grid(*b.link, m, o.g, note, [&](int done, int) {
    if (o.json) return;
    if (done == 0)
      std::printf("probing %d x %d points over X%s..%s Y%s..%s on %s\n", o.g.nx, o.g.ny,
                  format_number(o.g.x0).c_str(), format_number(o.g.x1).c_str(), format_number(o.g.y0).c_str(),
                  format_number(o.g.y1).c_str(), b.where.c_str());
    else
      std::printf("\r%d of %d points", done, total);
    std::fflush(stdout);
  });
  std::ofstream(o.out) << mc::machine::format_height_map(g.map);
  double lo = 0, hi = 0;
  for (double z : g.map.z) {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  if (o.json) {
    nlohmann::ordered_json j;
    j["map"] = o.out;
    j["points"] = total;
    j["z0_mm"] = g.z0_mm;
    j["lowest_mm"] = lo;
    j["highest_mm"] = hi;
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::printf(
      "\nwrote %s: heights %.4f .. %.4f mm relative to the first point (X%s Y%s), whose face is at machine Z "
      "%.4f mm\n",
      o.out.c_str(), lo, hi, format_number(o.g.x0).c_str(), format_number(o.g.y0).c_str(), g.z0_mm);
  std::printf("zero the work's Z there (e.g. G10 L2 P1 Z%.4f), then: motionctl run JOB --level %s\n", g.z0_mm,
              o.out.c_str());
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
      "mm apart (%s)\n",
      o.c.depth_mm, o.c.rows, o.c.columns, o.c.feed_mm_min, r.map.nx, r.map.ny, r.map.dx, r.map.dy,
      o.c.probe ? "probed on the board" : "a perfect probe's");
  std::printf("depth error: measured Z - (face - depth) along the cuts, um (+ too shallow)\n");
  std::printf("%-26s %9s %9s %10s %12s %8s %10s\n", "levelling", "RMS", "max |e|", "deepest", "shallowest",
              "samples", "underruns");
  for (const mc::machine::LevelCompareRun& x : r.runs)
    std::printf("%-26s %9.1f %9.1f %10.1f %12.1f %8zu %10d\n", x.method.c_str(), x.depth.rms_mm * 1e3,
                x.depth.max_mm * 1e3, x.depth.min_mm * 1e3, x.depth.worst_mm * 1e3, x.depth.n, x.underruns);
}

}  // namespace

void add_level_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("level", "Bed levelling: probe a height map, compare methods");
  cmd->require_subcommand(1);
  auto po = std::make_shared<ProbeOptions>();
  CLI::App* p = cmd->add_subcommand("probe", "Probe the bed on a grid into a height-map file");
  p->footer(
      std::string(kBoardFooter) +
      "\nStart with the tool above the work. The probe goes down at each grid point (row by row, back\n"
      "and forth) until it closes; between points the tool rises --clearance above the highest contact.\n"
      "Heights are relative to the first point (X0, Y0): zero Z there. docs/levelling.md has the format.");
  p->add_option("--grid", po->grid, "Points NxM along X and Y (default 3x3)")->type_name("NxM");
  p->add_option("--area", po->area, "X0,Y0,X1,Y1: the grid's corners, machine mm")
      ->type_name("X0,Y0,X1,Y1")
      ->required();
  p->add_option("-o,--output", po->out, "The height map to write (TOML)")->type_name("FILE")->required();
  p->add_option("--feed", po->g.feed_mm_min, "Probing feed, mm/min (default 300)")->type_name("MM/MIN");
  p->add_option("--travel-feed", po->g.travel_mm_min, "Moves between points, mm/min (default 1500)")
      ->type_name("MM/MIN");
  p->add_option("--clearance", po->g.clearance_mm, "mm above the highest contact between points (default 2)")
      ->type_name("MM");
  p->add_option("--distance", po->g.depth_mm, "mm below the start to search at each point (default 20)")
      ->type_name("MM");
  p->add_flag("--json", po->json, "One JSON object");
  p->callback([po] { probe(*po); });

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
  c->add_flag("--probe", o->c.probe, "Probe the map on the board instead (as level probe does)");
  c->add_option("--map", o->map_out, "Also write the map (TOML, docs/levelling.md)")->type_name("FILE");
  c->add_option("--program", o->program_out, "Also write the engraving (G-code)")->type_name("FILE");
  c->callback([o] { compare(*o); });
}

}  // namespace mc::host::cli
