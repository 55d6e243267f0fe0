// motionctl home | probe: the machine cycles a job starts with
// (host/machine/cycles.hpp), on the board or the virtual board.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/cycles.hpp"
#include "host/machine/job.hpp"
#include "host/machine/limits.hpp"

namespace mc::host::cli {
namespace {

// ---- home -------------------------------------------------------------------------

void home(const std::string& axis, bool json) {
  const mc::machine::MachineConfig m = machine();
  unsigned mask = 0;
  if (!axis.empty()) {
    mask = 1u << parse_axis(axis);
  } else {
    for (size_t a = 0; a < m.axes.size() && a < 3; ++a)
      if (m.axes[a].home) mask |= 1u << a;
    if (!mask)
      throw InputError("machine config", m.source, "an [axis.N.home] table", "no axis has a home switch");
  }
  const mc::machine::HomingPlan plan = mc::machine::homing_plan(m, mask);  // refused before the board moves
  Board b = open_board();
  BoardLink& l = *b.link;
  if (!json) {
    std::printf("homing on %s:", b.where.c_str());
    for (const auto& pass : plan.passes) {
      std::printf(" ");
      for (const auto& x : pass) std::printf("%s", axis_name(x.axis));
    }
    std::printf(" (passes in order)\n");
    std::fflush(stdout);
  }
  mc::machine::HomingCycle c(l, m, plan, note);
  while (!c.poll()) mc::machine::wait_on_link(l);
  const MachineOrigin org = read_origin(l);
  nlohmann::ordered_json j = nlohmann::json::array();
  for (const auto& pass : plan.passes)
    for (const auto& x : pass) {
      const int a = x.axis;
      const double at_mm = org.mm(a, int32_t(l.read(board::reg::axis(a, board::reg::AX_POS))),
                                  mc::machine::counts_per_m(m.axes[size_t(a)]));
      j.push_back({{"axis", axis_name(a)},
                   {"origin", org.counts[size_t(a)]},
                   {"switch_mm", x.switch_mm},
                   {"position_mm", at_mm}});
      if (!json)
        std::printf("%s: switch at machine %.4f mm; machine zero at board count %lld; now at %.4f mm\n",
                    axis_name(a), x.switch_mm, static_cast<long long>(org.counts[size_t(a)]), at_mm);
    }
  if (json) std::cout << j.dump(2) << '\n';
}

// ---- probe ------------------------------------------------------------------------

struct ProbeOptions {
  std::string axis = "z";
  double plate_mm = 0, feed_mm_min = 100, distance_mm = 20, retract_mm = 2;
  bool json = false;
};

void probe(const ProbeOptions& o) {
  const mc::machine::MachineConfig m = machine();
  const int a = parse_axis(o.axis, "axis");
  if (a >= int(m.axes.size()))
    throw InputError("axis", quote(o.axis), "an axis of the machine config (" + m.source + ")");
  for (const auto& [opt, v] : {std::pair{"--feed", o.feed_mm_min}, std::pair{"--distance", o.distance_mm}})
    if (!(v > 0) || !std::isfinite(v)) throw InputError(opt, format_number(v), "above 0");
  if (!(o.plate_mm >= 0) || !(o.retract_mm >= 0))
    throw InputError("--plate-thickness/--retract", format_number(std::min(o.plate_mm, o.retract_mm)),
                     "0 or more");
  const double cpmm = mc::machine::counts_per_m(m.axes[size_t(a)]) * 1e-3;
  mc::machine::check_feed(m, {}, {a == 0 ? 1 : 0, a == 1 ? 1 : 0, a == 2 ? 1 : 0}, o.feed_mm_min,
                          {"--feed", format_number(o.feed_mm_min)});
  Board b = open_board();
  BoardLink& l = *b.link;
  const mc::machine::JobBoard jb = mc::machine::ready_board(l, m, note);
  const MachineOrigin org = read_origin(l);
  // Down the axis (towards -): a Z probe touches the work below the tool.
  Vec3 to = jb.at;
  to[size_t(a)] -= mc::machine::counts_of(o.distance_mm, cpmm * 1e3);
  mc::machine::check_travel(m, org.machine(jb.at), org.machine(to),
                            {"--distance", format_number(o.distance_mm)});
  mc::machine::ProbeCycle c(l, jb.at, to, o.feed_mm_min / 60 * cpmm, true, 7);
  while (!c.poll()) mc::machine::wait_on_link(l);
  if (!c.contact())
    throw mc::machine::CycleError(5, "probe: no contact within " + format_number(o.distance_mm) + " mm");
  const double touch_mm = org.mm(a, c.position()[size_t(a)], cpmm * 1e3);
  // Back off the plate so that it can be taken away.
  Vec3 back = c.end();
  back[size_t(a)] += mc::machine::counts_of(o.retract_mm, cpmm * 1e3);
  mc::machine::LatchedMove r(l, {c.end(), back, o.feed_mm_min / 60 * cpmm * 4, {}, 0, false});
  while (!r.poll()) mc::machine::wait_on_link(l);
  const double zero_mm = touch_mm - o.plate_mm;
  if (o.json) {
    nlohmann::ordered_json j;
    j["axis"] = axis_name(a);
    j["contact_mm"] = touch_mm;
    j["plate_thickness_mm"] = o.plate_mm;
    j["work_zero_mm"] = zero_mm;
    j["homed"] = org.is_homed(a);
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::printf(
      "%s touched at machine %.4f mm%s; the work's zero (the plate's %.3f mm below) is at machine "
      "%.4f mm\n",
      axis_name(a), touch_mm, org.is_homed(a) ? "" : " (not homed: from where the axis was at power-up)",
      o.plate_mm, zero_mm);
  std::printf("a program sets it with: G10 L2 P1 %c%.4f\n", "XYZ"[a], zero_mm);
}

}  // namespace

void add_cycle_commands(CLI::App& app) {
  auto axis = std::make_shared<std::string>();
  auto hjson = std::make_shared<bool>(false);
  CLI::App* h = app.add_subcommand("home", "Home the axes on their switches and set machine zero");
  h->footer(
      std::string(kBoardFooter) +
      "\nEach axis with an [axis.N.home] table seeks its switch, backs off, locates it slowly and sets\n"
      "machine zero so that the switch is at its switch_m; passes by `order`. The origin is kept on the\n"
      "board (ORIGIN, HOMED) until it powers down: every later command and the Grbl server use it.");
  h->add_option("--axis", *axis, "x, y or z (default: every axis with a home switch)")->type_name("AXIS");
  h->add_flag("--json", *hjson, "One JSON array");
  h->callback([axis, hjson] { home(*axis, *hjson); });

  auto po = std::make_shared<ProbeOptions>();
  CLI::App* p = app.add_subcommand("probe", "Touch-plate probe: move an axis down until the probe closes");
  p->footer(
      std::string(kBoardFooter) +
      "\nMoves the axis towards - at --feed until the probe input closes (up to --distance), reports the\n"
      "contact, where the work's zero is under a plate of --plate-thickness, and backs off --retract.");
  p->add_option("axis", po->axis, "x, y or z (default z)")->type_name("AXIS");
  p->add_option("--plate-thickness", po->plate_mm, "mm (default 0: probing the work itself)")
      ->type_name("MM");
  p->add_option("--feed", po->feed_mm_min, "mm/min (default 100)")->type_name("MM/MIN");
  p->add_option("--distance", po->distance_mm, "mm to search (default 20)")->type_name("MM");
  p->add_option("--retract", po->retract_mm, "mm to back off after the contact (default 2)")->type_name("MM");
  p->add_flag("--json", po->json, "One JSON object");
  p->callback([po] { probe(*po); });
}

}  // namespace mc::host::cli
