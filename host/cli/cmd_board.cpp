// motionctl enable | disable | clear-fault | jog | move: the board
// commands that need only the link (--port DEV or --sim before the command).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/control/board_gains.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/limits.hpp"
#include "host/motion/board_run.hpp"

namespace mc::host::cli {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

// ---- enable / disable / clear-fault ------------------------------------------------
std::vector<int> axes_of(const std::string& axis, int naxes) {
  if (!axis.empty()) {
    const int a = parse_axis(axis);
    if (a >= naxes)
      throw InputError("--axis", quote(axis), "one of the board's " + std::to_string(naxes) + " axes");
    return {a};
  }
  // Every axis the machine has: a board axis without a motor stays off.
  std::vector<int> v;
  const auto sc = axis_scales();
  for (int a = 0; a < naxes; ++a)
    if (sc[size_t(a)] > 0) v.push_back(a);
  return v;
}

// "--axis ''" (an empty variable in a script) must not mean "every axis".
void refuse_empty_axis(const CLI::Option& opt, const std::string& axis) {
  if (opt.count() > 0 && axis.empty())
    throw InputError("--axis", "\"\"", "an axis name: x, y or z (leave --axis out for every axis)");
}

void enable(const std::string& axis, bool json) {
  if (!axis.empty()) parse_axis(axis);  // a bad name is an error before any port is opened
  Board b = open_board();
  BoardLink& l = *b.link;
  const int naxes = read_naxes(l);
  const std::vector<int> axes = axes_of(axis, naxes);
  mc::machine::enable_machine_axes(l, machine(), axes, note);
  mc::machine::arm_following_limits(l, machine());
  const BoardState s = read_state(l);
  if (json) {
    nlohmann::ordered_json j;
    j["enabled"] = nlohmann::json::array();
    for (int a : axes) j["enabled"].push_back(axis_name(a));
    j["armed"] = true;
    j["watchdog"] = watchdog_text(s);
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::string names;
  for (int a : axes) names += (names.empty() ? "" : ", ") + std::string(axis_name(a));
  std::cout << "enabled " << names << "; drives armed.\n"
            << "The board's watchdog turns the drives off " << watchdog_text(s)
            << " after the last frame: they go off when this command exits, by design.\n"
            << "jog and move arm them again for their motion.\n";
}

void disable(const std::string& axis, bool json) {
  if (!axis.empty()) parse_axis(axis);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int naxes = read_naxes(l);
  const std::vector<int> axes = axes_of(axis, naxes);
  mc::machine::require_disable_alone(machine(), axes, !axis.empty());
  disable_axes(l, axes, axis.empty());
  if (json) {
    nlohmann::ordered_json j;
    j["disabled"] = nlohmann::json::array();
    for (int a : axes) j["disabled"].push_back(axis_name(a));
    j["drives_off"] = axis.empty();
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::cout << (axis.empty() ? "drives off, every axis disabled\n" : "disabled " + axis + "\n");
}

void clear_fault(bool json) {
  Board b = open_board();
  BoardLink& l = *b.link;
  const uint32_t f = clear_faults(l);
  if (json) {
    nlohmann::ordered_json j;
    j["cleared"] = f == 0 ? "" : fault_names(f);
    j["fault_word"] = f;
    std::cout << j.dump(2) << '\n';
  } else if (f == 0) {
    std::cout << "no fault latched\n";
  } else {
    std::cout << "cleared: " << fault_names(f) << " (the drives stay off until enable, jog or move)\n";
  }
}

// ---- jog / move -------------------------------------------------------------------

struct MotionOptions {
  std::string axis, distance, feed, target;
  bool json = false;
};

// `asked` names the option that sets the target, for a move beyond the travel.
void move_to(BoardLink& l, const std::function<Vec3(const Vec3&, const std::array<double, 3>&)>& target,
             const mc::machine::Asked& asked, const std::string& feed_text, bool json) {
  const double feed_mm_min = parse_number(feed_text, "--feed");
  if (!(feed_mm_min > 0)) throw InputError("--feed", quote(feed_text), "a feed above 0 mm/min");
  const auto scale = axis_scales();
  // The machine's travel and speeds, checked before the drives are armed.
  // in machine counts: the board's counts less its origin (homing sets it).
  const mc::machine::MachineConfig m = machine();
  const MachineOrigin org = read_origin(l);
  const Vec3 from = org.machine(start_position(l));
  const Vec3 to = target(from, scale);
  mc::machine::check_travel(m, from, to, asked);
  mc::machine::check_feed(m, from, to, feed_mm_min, {"--feed", feed_text});
  const MoveResult r = move_axes(
      l, [&](const Vec3& at) { return org.board(target(org.machine(at), scale)); }, feed_mm_min, scale, note);
  if (!r.moved) {
    std::cout << (json ? "{\n  \"moved\": false\n}\n" : "already there\n");
    return;
  }
  nlohmann::ordered_json j;
  j["moved"] = true;
  j["axes"] = nlohmann::json::array();
  std::string line = "done:";
  for (int a = 0; a < 3; ++a) {
    if (scale[size_t(a)] == 0) continue;
    const double pos_mm = org.mm(a, r.pos[size_t(a)], scale[size_t(a)]),
                 cmd_mm = org.mm(a, r.to[size_t(a)], scale[size_t(a)]);
    j["axes"].push_back({{"axis", axis_name(a)}, {"position_mm", pos_mm}, {"command_mm", cmd_mm}});
    char b[96];
    std::snprintf(b, sizeof b, " %s %.4f mm (command %.4f)", axis_name(a), pos_mm, cmd_mm);
    line += b;
  }
  std::cout << (json ? j.dump(2) : line) << '\n';
}

void jog(const MotionOptions& o) {
  const int a = parse_axis(o.axis);
  const double mm = parse_number(o.distance, "--distance");
  if (axis_scales()[size_t(a)] == 0)
    throw InputError("--axis", quote(o.axis), "an axis of the machine config (" + machine().source + ")");
  Board b = open_board();
  mc::machine::require_ready(*b.link, machine(), a);
  move_to(
      *b.link,
      [&](const Vec3& from, const std::array<double, 3>& s) {
        Vec3 to = from;
        to[size_t(a)] += mc::machine::counts_of(mm, s[size_t(a)]);
        return to;
      },
      {"--distance", o.distance}, o.feed, o.json);
}

void move(const MotionOptions& o) {
  std::vector<double> mm;
  std::stringstream ss(o.target);
  for (std::string part; std::getline(ss, part, ',');) mm.push_back(parse_number(part, "target"));
  if (mm.size() < 2 || mm.size() > 3) throw InputError("target", quote(o.target), "X,Y or X,Y,Z in mm");
  const auto sc = axis_scales();
  for (size_t a = 0; a < mm.size(); ++a)
    if (sc[a] == 0)
      throw InputError("target", quote(o.target),
                       "no coordinate for axis " + std::string(axis_name(int(a))) +
                           ", which the machine config (" + machine().source + ") does not describe");
  Board b = open_board();
  for (size_t a = 0; a < mm.size(); ++a) mc::machine::require_ready(*b.link, machine(), int(a));
  move_to(
      *b.link,
      [&](const Vec3& from, const std::array<double, 3>& s) {
        Vec3 to = from;
        for (size_t a = 0; a < mm.size(); ++a) to[a] = mc::machine::counts_of(mm[a], s[a]);
        return to;
      },
      {"target", o.target}, o.feed, o.json);
}

}  // namespace

void add_board_commands(CLI::App& app) {
  auto axis = std::make_shared<std::string>();
  CLI::App* en = app.add_subcommand("enable", "Enable the PID of an axis (default: all) and arm the drives");
  en->footer(
      std::string(kBoardFooter) +
      "\nThe watchdog turns the drives off one WDOG period (100 ms by default) after the last frame, so\n"
      "they go off when this command exits: the intended safety behaviour. jog and move arm again.");
  CLI::Option* eaxis =
      en->add_option("--axis", *axis, "x, y or z (default: every axis of the machine config)")
          ->type_name("AXIS");
  auto ejson = std::make_shared<bool>(false);
  en->add_flag("--json", *ejson, "One JSON object");
  en->callback([axis, eaxis, ejson] {
    refuse_empty_axis(*eaxis, *axis);
    enable(*axis, *ejson);
  });

  auto daxis = std::make_shared<std::string>();
  CLI::App* dis = app.add_subcommand("disable", "Disable the PID of an axis; without --axis also disarm");
  dis->footer(kBoardFooter);
  CLI::Option* daxis_opt =
      dis->add_option("--axis", *daxis, "x, y or z (default: every axis, and the drives off)")
          ->type_name("AXIS");
  auto djson = std::make_shared<bool>(false);
  dis->add_flag("--json", *djson, "One JSON object");
  dis->callback([daxis, daxis_opt, djson] {
    refuse_empty_axis(*daxis_opt, *daxis);
    disable(*daxis, *djson);
  });

  CLI::App* cf = app.add_subcommand("clear-fault", "Clear the latched faults whose cause is gone");
  cf->footer(kBoardFooter);
  auto cjson = std::make_shared<bool>(false);
  cf->add_flag("--json", *cjson, "One JSON object");
  cf->callback([cjson] { clear_fault(*cjson); });

  auto jo = std::make_shared<MotionOptions>();
  CLI::App* jg = app.add_subcommand("jog", "Move one axis by a distance at a feed, and wait until done");
  jg->footer(std::string(kBoardFooter) +
             "\nArms the drives (clearing a watchdog fault left by the previous command), starts from where\n"
             "the axes are, and keeps the link alive until the move is done. Refused before anything moves:\n"
             "a target beyond an axis' travel_min_m..travel_max_m, a feed that drives an axis above its\n"
             "max_speed_m_s (the machine TOML).");
  jg->add_option("--axis", jo->axis, "x, y or z")->required()->type_name("AXIS");
  jg->add_option("--distance", jo->distance, "mm, signed")->required()->type_name("MM");
  jg->add_option("--feed", jo->feed, "mm/min along the path")->required()->type_name("MM/MIN");
  jg->add_flag("--json", jo->json, "One JSON object");
  jg->callback([jo] { jog(*jo); });

  auto mo = std::make_shared<MotionOptions>();
  CLI::App* mv = app.add_subcommand("move", "Move to X,Y[,Z] (mm, machine coordinates) in a straight line");
  mv->footer(jg->get_footer());
  mv->add_option("target", mo->target, "X,Y or X,Y,Z in mm")->required()->type_name("X,Y[,Z]");
  mv->add_option("--feed", mo->feed, "mm/min along the path")->required()->type_name("MM/MIN");
  mv->add_flag("--json", mo->json, "One JSON object");
  mv->callback([mo] { move(*mo); });
}

}  // namespace mc::host::cli
