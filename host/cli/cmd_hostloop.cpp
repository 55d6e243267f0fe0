// motionctl hostloop: the PC's control loop run live against the board,
// then the board's own loop on the same move.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/control/board_experiments.hpp"
#include "host/control/board_gains.hpp"
#include "host/control/pid_double.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/limits.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::host::cli {
namespace {

// ---- hostloop -----------------------------------------------------------------------
struct HostloopOptions {
  std::string axis, ts = "10ms", duration = "0.6s", distance = "2", feed = "600";
  bool json = false;
};

void hostloop(const HostloopOptions& o) {
  const int a0 = parse_axis(o.axis);
  mc::machine::require_servo(machine(), a0, "motionctl hostloop");
  const double ts_host = parse_duration(o.ts, "--ts");
  const double duration = parse_duration(o.duration, "--duration");
  if (duration > 10) throw InputError("--duration", quote(o.duration), "at most 10 s");
  const double mm = parse_number(o.distance, "--distance");
  const double feed = parse_number(o.feed, "--feed");
  if (!(feed > 0)) throw InputError("--feed", quote(o.feed), "a feed above 0 mm/min");
  const double cpm = machine_scale(a0, o.axis);
  const mc::machine::MachineConfig mach = machine();
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  const AxisGains cur = read_gains(l, a);
  const double ts = cur.gains.ts;
  const int64_t every = std::llround(ts_host / ts);
  if (every < 1 || std::fabs(double(every) * ts - ts_host) > 1e-9)
    throw InputError("--ts", quote(o.ts), "a whole number of the board's Ts (" + format_duration(ts) + ")");
  // Two replies per host sample (the DRV write, the TLM_HDR read); the
  // host's samples must fall on frames.
  uint32_t decim = telemetry_decimation(l, ts, 2);
  while (every % decim != 0 && int64_t(decim) < every) ++decim;
  if (every % decim != 0) decim = uint32_t(every);
  const double delay = ts_host / 2 + mach.host_io_latency_s;
  const PidGains g = mc::machine::tuned_gains(mach.axes.at(size_t(a)), ts_host, delay);
  const double olim = cur.limits.out_limit ? double(cur.limits.out_limit) : 32767;
  mc::host::PidDouble pid(g, olim);
  const int64_t move = mc::machine::counts_of(mm, cpm);
  if (move == 0) throw InputError("--distance", quote(o.distance), "a move of at least one count");
  // The jog out and back: within travel and the axis' speed, before arming.
  const Vec3 from = start_position(l);
  Vec3 to = from;
  to[size_t(a)] += move;
  mc::machine::check_travel(mach, from, to, {"--distance", o.distance});
  mc::machine::check_feed(mach, from, to, feed, {"--feed", o.feed});
  const auto counts = int32_t(move);  // within travel, so within 32 bits
  enable_axes(l, {a}, note);
  mc::machine::arm_following_limits(l, mach);
  catch_interrupts();
  const int64_t samples = std::llround(duration / ts);
  const double fc = feed / 60e3 * cpm;
  const LoopRun host = run_jog(l, a, counts, fc, decim, samples, every, &pid, note);
  const LoopRun fpga = run_jog(l, a, -counts, fc, decim, samples, 0, nullptr, note);
  const Dist per = dist(host.period_s, ts), lat = dist(host.latency_s, ts),
             wall = dist(host.wall_period_s, 1);
  const double um = 1e6 / cpm;
  if (o.json) {
    nlohmann::ordered_json j;
    j["axis"] = axis_name(a);
    j["ts_host_s"] = ts_host;
    j["ts_board_s"] = ts;
    j["host_gains"] = pid_json(g);
    j["decimation"] = decim;
    j["host_samples"] = host.period_s.size() + 1;
    j["period_board_s"] = {{"mean", per.mean}, {"p99", per.p99}, {"max", per.max}};
    j["latency_board_s"] = {{"mean", lat.mean}, {"p99", lat.p99}, {"max", lat.max}};
    j["period_wall_s"] = {{"mean", wall.mean}, {"p99", wall.p99}, {"max", wall.max}};
    j["host_following_error_um"] = {{"rms", host.follow.rms * um}, {"max", host.follow.max * um}};
    j["fpga_following_error_um"] = {{"rms", fpga.follow.rms * um}, {"max", fpga.follow.max * um}};
    j["gaps"] = host.gaps + fpga.gaps;
    j["faults"] = fault_names(uint32_t(host.fault | fpga.fault));
    std::cout << j.dump(2) << '\n';
    return;
  }
  char line[400];
  std::snprintf(
      line, sizeof line,
      "host loop on axis %s: PID in double precision every %s of board time (paced by telemetry, every "
      "%u board samples per frame), drive through the DRV override\n  gains (machine::tuned_gains for a "
      "%s delay): %s\n",
      axis_name(a), format_duration(ts_host).c_str(), decim, format_duration(delay).c_str(),
      gains_line(g).c_str());
  std::cout << line;
  std::snprintf(line, sizeof line,
                "  %zu host samples; period (board time, resolution %s): mean %s, p99 %s, max %s\n"
                "  latency frame -> drive written (board time): mean %s, p99 %s, max %s\n"
                "  host wall-clock period: mean %s, p99 %s, max %s%s\n",
                host.period_s.size() + 1, format_duration(ts).c_str(), format_duration(per.mean).c_str(),
                format_duration(per.p99).c_str(), format_duration(per.max).c_str(),
                format_duration(lat.mean).c_str(), format_duration(lat.p99).c_str(),
                format_duration(lat.max).c_str(), format_duration(wall.mean).c_str(),
                format_duration(wall.p99).c_str(), format_duration(wall.max).c_str(),
                // A virtual board running free, or slower than the wall clock, stretches it.
                wall.mean > 1.5 * per.mean || wall.mean < per.mean / 1.5
                    ? " (the board's clock is not the wall clock's)"
                    : "");
  std::cout << line;
  std::snprintf(
      line, sizeof line,
      "following error, %.3g mm jog at %.4g mm/min, %s captured:\n  host loop %s: RMS %.1f um, max %.1f "
      "um\n  FPGA loop %s: RMS %.1f um, max %.1f um (the board's own PID, same move back)\n",
      mm, feed, format_duration(duration).c_str(), format_duration(ts_host).c_str(), host.follow.rms * um,
      host.follow.max * um, format_duration(ts).c_str(), fpga.follow.rms * um, fpga.follow.max * um);
  std::cout << line;
  if (host.gaps + fpga.gaps) std::cout << "telemetry gaps: " << host.gaps + fpga.gaps << '\n';
  if (host.fault | fpga.fault)
    std::cout << "FAULT: " << fault_names(uint32_t(host.fault | fpga.fault)) << '\n';
}

}  // namespace

void add_hostloop_command(CLI::App& app) {
  auto h = std::make_shared<HostloopOptions>();
  CLI::App* hl =
      app.add_subcommand("hostloop", "The PC's control loop, live: the host runs the PID, the board moves");
  hl->footer(
      std::string(kBoardFooter) +
      "\nThe board's PID output is bypassed (DRV override); every --ts of BOARD time (telemetry frames\n"
      "are the clock) the host runs the same PID in double precision on the streamed CMD and POS and\n"
      "writes the drive. A jog of --distance at --feed runs under the host loop, then the same move back\n"
      "under the board's PID. Reports the host's periods and latency (board time) and both following\n"
      "errors. docs/motionctl.md says what the jitter means on the virtual board.");
  hl->add_option("--axis", h->axis, "x, y or z")->required()->type_name("AXIS");
  hl->add_option("--ts", h->ts, "Host loop period, a whole number of the board's Ts (default 10ms)")
      ->type_name("TIME");
  hl->add_option("--duration", h->duration, "Capture per run, board time (default 0.6s)")->type_name("TIME");
  hl->add_option("--distance", h->distance, "Jog, mm (default 2)")->type_name("MM");
  hl->add_option("--feed", h->feed, "mm/min (default 600)")->type_name("MM/MIN");
  hl->add_flag("--json", h->json, "One JSON object");
  hl->callback([h] { hostloop(*h); });
}

}  // namespace mc::host::cli
