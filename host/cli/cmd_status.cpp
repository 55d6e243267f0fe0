// motionctl status: the board's state, per axis and as a whole.
#include <CLI/CLI.hpp>
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
#include "host/machine/mpg.hpp"
#include "host/motion/board_run.hpp"

namespace mc::host::cli {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

// ---- status -------------------------------------------------------------------
void status(bool json) {
  Board b = open_board();
  const BoardState s = read_state(*b.link);
  const auto scale = axis_scales();
  const LinkCounters& c = b.link->counters();
  const uint32_t info = b.link->read(br::INFO);
  // Counts are the board's (from power-up); mm are machine coordinates,
  // from the origin a homing cycle set (none: from power-up as well).
  const MachineOrigin org = read_origin(*b.link);
  const mc::machine::MpgSetting mpg = mc::machine::read_mpg(*b.link);
  const int32_t mpg_pending = mc::machine::mpg_pending(*b.link);
  if (json) {
    nlohmann::ordered_json j;
    j["port"] = b.port->name();
    j["id"] = s.id;
    j["build"] = {{"servo", bb::info_servo(info)},
                  {"steppers", bb::info_steppers(info)},
                  {"handwheel", bb::info_handwheel(info)}};
    j["clock_hz"] = s.clk_hz;
    j["ts_s"] = s.ts_s();
    j["ts_cycles"] = s.ts_cycles;
    j["watchdog_s"] = double(s.wdog) / s.clk_hz;
    j["armed"] = s.armed();
    j["fault"] = s.fault;
    j["faults"] = nlohmann::json::array();
    if (s.fault) {
      std::stringstream names(fault_names(s.fault));
      for (std::string n; std::getline(names, n, ',');) j["faults"].push_back(n.substr(n[0] == ' '));
    }
    j["interpolator"] = {{"busy", bool(s.ip_stat >> bb::IS_BUSY & 1)},
                         {"words_queued", s.ip_stat & 0xFFFF},
                         {"segments_done", s.ip_segs & 0xFFFF}};
    j["axes"] = nlohmann::json::array();
    for (int a = 0; a < s.naxes; ++a) {
      const AxisState& x = s.axes[size_t(a)];
      nlohmann::ordered_json ja;
      ja["axis"] = axis_name(a);
      ja["position"] = x.pos;
      ja["command"] = x.cmd;
      ja["error"] = x.err;
      ja["output"] = x.u;
      ja["saturated"] = x.sat;
      ja["enabled"] = x.pid_en;
      ja["drive"] = x.drv_en;
      ja["homed"] = org.is_homed(a);
      ja["origin"] = org.counts[size_t(a)];
      if (scale[size_t(a)] > 0) {
        ja["position_mm"] = org.mm(a, x.pos, scale[size_t(a)]);
        ja["command_mm"] = org.mm(a, x.cmd, scale[size_t(a)]);
      }
      j["axes"].push_back(ja);
    }
    j["handwheel"] = {{"setting", mc::machine::mpg_text(mpg)}, {"pending_counts", mpg_pending}};
    j["link"] = {{"board_crc_errors", s.link_crc & 0xFFFF},  {"board_framing_errors", s.link_crc >> 16},
                 {"board_refused", s.link_cmd & 0xFFFF},     {"board_duplicates", s.link_cmd >> 16},
                 {"board_junk_bytes", s.link_junk & 0xFFFF}, {"host_requests", c.requests},
                 {"host_retransmits", c.retransmits},        {"host_crc_errors", c.rx.crc},
                 {"host_round_trip_ms", c.srtt_ms}};
    std::cout << j.dump(2) << '\n';
    return;
  }
  char line[300];
  std::cout << "board at " << b.where << ": clock " << s.clk_hz << " Hz, Ts " << format_duration(s.ts_s())
            << " (" << s.ts_cycles << " cycles), watchdog " << watchdog_text(s) << '\n'
            << "built with " << build_text(info) << '\n';
  std::cout << "drives " << (s.armed() ? "ARMED" : "off") << ", faults: " << fault_names(s.fault)
            << ", interpolator " << ((s.ip_stat >> bb::IS_BUSY & 1) ? "busy" : "idle") << " ("
            << (s.ip_stat & 0xFFFF) << " words queued, " << (s.ip_segs & 0xFFFF) << " segments done)\n";
  std::snprintf(line, sizeof line, "%-4s %12s %12s %8s %7s %4s %7s %5s %12s %6s\n", "axis", "position",
                "command", "error", "output", "sat", "enabled", "drive", "machine mm", "homed");
  std::cout << line;
  for (int a = 0; a < s.naxes; ++a) {
    const AxisState& x = s.axes[size_t(a)];
    char mm[32] = "-";
    if (scale[size_t(a)] > 0) std::snprintf(mm, sizeof mm, "%.4f", org.mm(a, x.pos, scale[size_t(a)]));
    std::snprintf(line, sizeof line, "%-4s %12d %12d %8d %7d %4s %7s %5s %12s %6s\n", axis_name(a),
                  int(x.pos), int(x.cmd), int(x.err), int(x.u), x.sat ? "yes" : "no", x.pid_en ? "yes" : "no",
                  x.drv_en ? "on" : "off", mm, org.is_homed(a) ? "yes" : "no");
    std::cout << line;
  }
  std::cout << "handwheel " << mc::machine::mpg_text(mpg) << ", " << mpg_pending << " counts pending\n";
  std::snprintf(line, sizeof line,
                "link: board counted %u CRC errors, %u framing errors, %u refused, %u duplicates, %u junk "
                "bytes; this run %llu requests, %llu retransmits, round trip %.1f ms\n",
                unsigned(s.link_crc & 0xFFFF), unsigned(s.link_crc >> 16), unsigned(s.link_cmd & 0xFFFF),
                unsigned(s.link_cmd >> 16), unsigned(s.link_junk & 0xFFFF),
                static_cast<unsigned long long>(c.requests), static_cast<unsigned long long>(c.retransmits),
                c.srtt_ms);
  std::cout << line;
}

}  // namespace

void add_status_command(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* st =
      app.add_subcommand("status", "Board state: per axis position, command, error, output; faults");
  st->footer(kBoardFooter);
  st->add_flag("--json", *json, "One JSON object instead of the table");
  st->callback([json] { status(*json); });
}

}  // namespace mc::host::cli
