// motionctl mpg: the handwheel jog (host/machine/mpg.hpp): which axis the
// wheel moves and how many counts a detent, shown in mm for the machine;
// with --seconds it also holds the drives armed while the wheel turns.
#include <CLI/CLI.hpp>
#include <array>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/mpg.hpp"

namespace mc::host::cli {
namespace {

namespace mm = mc::machine;

struct MpgOptions {
  std::string axis, step, seconds;
  bool off = false, json = false;
};

// What the options ask for, checked before any port is opened: the new
// setting (nothing: keep the board's), and the hold time (0: none).
struct MpgRequest {
  std::optional<mm::MpgSetting> set;
  bool step_only = false;  // --step alone: the board's axis, this step
  double hold_s = 0;
};

MpgRequest parse(const MpgOptions& o) {
  MpgRequest r;
  if (o.off && (!o.axis.empty() || !o.step.empty() || !o.seconds.empty()))
    throw InputError("--off", "with --axis, --step or --seconds", "--off alone: it turns the handwheel off");
  if (o.off) r.set = mm::MpgSetting{};
  if (!o.axis.empty() || !o.step.empty()) {
    mm::MpgSetting s;
    s.step = o.step.empty() ? 0 : mm::parse_mpg_step(o.step, "--step");
    if (!o.axis.empty()) {
      s.axis = parse_axis(o.axis);
      if (axis_scales()[size_t(s.axis)] == 0)
        throw InputError("--axis", quote(o.axis), "an axis of the machine config (" + machine().source + ")");
    }
    r.step_only = o.axis.empty();
    r.set = s;
  }
  if (!o.seconds.empty()) r.hold_s = parse_duration(o.seconds, "--seconds");
  return r;
}

nlohmann::ordered_json setting_json(const mm::MachineConfig& m, const mm::MpgSetting& s, int32_t pending) {
  nlohmann::ordered_json j;
  j["on"] = s.on();
  if (s.on()) {
    j["axis"] = axis_name(s.axis);
    j["step_counts"] = s.step;
    j["mm_per_detent"] = mm::mm_per_detent(m, s);
    j["counts_per_mm"] = mm::counts_per_m(m.axes[size_t(s.axis)]) / 1e3;
  }
  j["pending_counts"] = pending;
  return j;
}

std::string setting_line(const mm::MachineConfig& m, const mm::MpgSetting& s, int32_t pending) {
  if (!s.on()) return "handwheel off";
  char line[200];
  std::snprintf(line, sizeof line,
                "handwheel on %s, x%d: %d count%s a detent = %.4g mm (%.6g counts/mm); %d pending",
                axis_name(s.axis), s.step, s.step, s.step == 1 ? "" : "s", mm::mm_per_detent(m, s),
                mm::counts_per_m(m.axes[size_t(s.axis)]) / 1e3, int(pending));
  return line;
}

void mpg(const MpgOptions& o) {
  MpgRequest r = parse(o);
  const mm::MachineConfig m = machine();
  Board b = open_board();
  BoardLink& l = *b.link;
  const int32_t dropped = r.set && !r.set->on() ? mm::mpg_pending(l) : 0;
  if (r.set) {
    mm::MpgSetting s = *r.set;
    const mm::MpgSetting now = mm::read_mpg(l);
    if (r.step_only) {
      if (!now.on()) throw InputError("--step", quote(o.step), "--axis too: the handwheel is off");
      s.axis = now.axis;
    }
    if (s.step == 0) s.step = now.on() ? now.step : 1;  // --axis alone keeps the step selected
    mm::set_mpg(l, m, s);
  }
  const mm::MpgSetting s = mm::read_mpg(l);
  nlohmann::ordered_json j = setting_json(m, s, mm::mpg_pending(l));
  if (r.set && !r.set->on()) j["dropped_counts"] = dropped;
  if (r.hold_s == 0) {
    if (o.json) {
      std::cout << j.dump(2) << '\n';
    } else {
      std::cout << setting_line(m, s, j["pending_counts"]) << '\n';
      if (r.set && !r.set->on() && dropped != 0) std::cout << "dropped " << dropped << " pending counts\n";
      if (s.on())
        std::cout << "The board moves the axis only while its drives are armed: hold them with --seconds T\n"
                     "(or run under a command that keeps the link, such as motionctl serve).\n";
    }
    return;
  }
  if (!s.on()) throw InputError("--seconds", quote(o.seconds), "a handwheel on: select it with --axis");
  mm::require_ready(l, m, s.axis);
  const std::array<int64_t, 3> start = arm(l, note);
  const MachineOrigin org = read_origin(l);
  const double scale = mm::counts_per_m(m.axes[size_t(s.axis)]);
  if (!o.json) {
    std::cout << setting_line(m, s, j["pending_counts"]) << "\ndrives armed for " << format_number(r.hold_s)
              << " s: turn the wheel\n"
              << std::flush;
  }
  const mm::MpgSample end = mm::follow_mpg(l, s.axis, r.hold_s, [&](const mm::MpgSample& x) {
    if (o.json) return;
    std::printf("%8.2f s  %s %10.4f mm (command %.4f), %d pending\n", x.wall_s, axis_name(s.axis),
                org.mm(s.axis, x.pos, scale), org.mm(s.axis, x.cmd, scale), int(x.pending));
    std::fflush(stdout);
  });
  if (o.json) {
    j["start_command"] = start[size_t(s.axis)];
    j["position"] = end.pos;
    j["command"] = end.cmd;
    j["position_mm"] = org.mm(s.axis, end.pos, scale);
    j["command_mm"] = org.mm(s.axis, end.cmd, scale);
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::printf(
      "done: %s %.4f mm (command %.4f); the drives go off with the watchdog, the handwheel stays on\n",
      axis_name(s.axis), org.mm(s.axis, end.pos, scale), org.mm(s.axis, end.cmd, scale));
}

}  // namespace

void add_mpg_command(CLI::App& app) {
  auto o = std::make_shared<MpgOptions>();
  CLI::App* c =
      app.add_subcommand("mpg", "The handwheel jog: the axis it moves, counts a detent, hold the drives");
  c->footer(
      std::string(kBoardFooter) +
      "\nSelects the axis the handwheel moves and its step: x1, x10, x100 are 1, 10, 100 encoder counts a\n"
      "detent (shown in mm for the machine config). The board does the jogging, and only while its drives\n"
      "are armed and no program runs: without --seconds the command sets the handwheel and returns (it\n"
      "stays on until --off); --seconds T also arms the drives and keeps the link alive for T seconds,\n"
      "printing the position as the wheel turns, then waits for the axis to finish what is pending.\n"
      "Without options: the board's setting. --axis alone keeps the step; --step alone keeps the axis.\n"
      "Switching axis or step, or --off, drops the counts still pending. On the virtual board:\n"
      "'motionctl sim wheel --detents N' turns the wheel.");
  c->add_option("--axis", o->axis, "x, y or z: the axis the wheel moves")->type_name("AXIS");
  c->add_option("--step", o->step, "Counts a detent: 1, 10 or 100")->type_name("1|10|100");
  c->add_option("--seconds", o->seconds, "Hold the drives armed this long while the wheel turns")
      ->type_name("TIME");
  c->add_flag("--off", o->off, "Turn the handwheel off (pending counts are dropped)");
  c->add_flag("--json", o->json, "One JSON object");
  c->callback([o] { mpg(*o); });
}

}  // namespace mc::host::cli
