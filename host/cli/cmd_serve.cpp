// motionctl serve: the Grbl 1.1 front end (host/grbl) on a pseudo-terminal
// and optionally TCP, so that cncjs, bCNC or UGS drive the machine. The
// machine behind it is built in make_backend(), the one place that chooses.
#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "host/grbl/board_backend.hpp"
#include "host/grbl/dry_run_backend.hpp"
#include "host/grbl/server.hpp"
#include "host/machine/height_map.hpp"

namespace mc::host::cli {
namespace {

struct ServeOptions {
  std::string pty;
  int tcp = -1;
  bool dry_run = false;
  std::string settings;
  int blocks = 16;
  std::string watchdog;  // empty: the board's
  std::string level;     // height map file: levelling on from the start
};

// The machine behind the Grbl front end and what moves it along between
// rounds of the server loop.
struct Machine {
  Board board;  // the link the board backend uses (none for --dry-run); outlives it
  std::unique_ptr<mc::grbl::Backend> backend;
  std::function<void()> tick;
  std::string what;
};

// ---------------------------------------------------------------------------
// THE place where the Grbl server's backend is constructed. --dry-run (or no
// --port/--sim) runs the kinematic dry-run machine on the wall clock; --port
// or --sim the board (or the virtual board) through the planner, one link
// round per round of the server loop.
// ---------------------------------------------------------------------------
Machine make_backend(const ServeOptions& o) {
  const GlobalOptions& g = global_options();
  if (o.dry_run || (g.port.empty() && !g.sim)) {
    auto dry = std::make_unique<mc::grbl::DryRunBackend>(o.blocks);
    mc::grbl::DryRunBackend* d = dry.get();
    auto last = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
    Machine m;
    m.tick = [d, last] {
      const auto now = std::chrono::steady_clock::now();
      d->advance(std::chrono::duration<double>(now - *last).count());
      *last = now;
    };
    m.backend = std::move(dry);
    m.what = "the dry-run machine (no hardware: moves are timed, nothing drives a motor)";
    return m;
  }
  const double wdog = o.watchdog.empty() ? 0.0 : parse_duration(o.watchdog, "--watchdog");
  if (wdog > 0) mc::grbl::watchdog_cycles(wdog, machine().clock_hz);  // refused before the board is touched
  Machine m;
  m.board = open_board();
  // The map first: a bad file is refused before the board is readied.
  std::optional<mc::machine::HeightMap> map;
  if (!o.level.empty()) map = mc::machine::load_height_map(o.level);
  auto board = std::make_unique<mc::grbl::BoardBackend>(*m.board.link, machine(), o.blocks, note, wdog);
  mc::grbl::BoardBackend* b = board.get();
  if (map) b->set_height_map(*map, o.level);
  m.tick = [b] { b->tick(); };
  m.backend = std::move(board);
  m.what = m.board.where;
  return m;
}

void run_serve(const ServeOptions& o) {
  if (o.pty.empty() && o.tcp < 0) throw InputError("--pty/--tcp", "neither given", "at least one of them");
  if (o.blocks < 1 || o.blocks > 255) throw InputError("--blocks", std::to_string(o.blocks), "1..255");
  if (!o.level.empty() && (o.dry_run || (global_options().port.empty() && !global_options().sim)))
    throw InputError("--level", o.level, "--port or --sim", "the dry-run machine does not level");
  const mc::machine::MachineConfig m = machine();
  mc::grbl::ServeConfig cfg;
  cfg.server.pty_link = o.pty;
  cfg.server.tcp_port = o.tcp;
  cfg.settings_path = o.settings.empty() ? mc::grbl::settings_path_for(global_options().config) : o.settings;
  cfg.defaults.settings = mc::grbl::default_settings(m);
  Machine machine_ = make_backend(o);
  const uint64_t lines =
      mc::grbl::serve(*machine_.backend, cfg, machine_.tick, [&](const mc::grbl::Server& s) {
        std::cout << "Grbl 1.1h front end for " << m.source << ", on " << machine_.what << "\n";
        if (!s.pty_path().empty()) std::cout << "  serial: " << o.pty << " -> " << s.pty_path() << "\n";
        if (s.tcp_port() >= 0) std::cout << "  tcp:    127.0.0.1:" << s.tcp_port() << "\n";
        std::cout << "  settings ($$, $#, $N): " << cfg.settings_path << "\nCtrl-C stops." << std::endl;
      });
  std::cout << "stopped after answering " << lines << " lines" << std::endl;
}

}  // namespace

void add_serve_command(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* c = app.add_subcommand(
      "serve", "Speak Grbl 1.1 to G-code senders (cncjs, bCNC, UGS) on a pseudo-terminal and/or TCP");
  c->add_option("--pty", o->pty, "Create this symlink to the pseudo-terminal, e.g. /tmp/motioncore")
      ->type_name("LINK");
  c->add_option("--tcp", o->tcp, "Also listen on 127.0.0.1:PORT (0: any free port)")->type_name("PORT");
  c->add_flag("--dry-run", o->dry_run,
              "Run on the kinematic dry-run machine (the default without --port/--sim)");
  c->add_option("--settings", o->settings,
                "Grbl settings file (default: next to --config as NAME.grbl.toml, else "
                "~/.config/motionctl/grbl.toml)")
      ->type_name("FILE");
  c->add_option("--blocks", o->blocks, "Planner blocks: lines queued ahead of the machine (default 16)")
      ->type_name("N");
  c->add_option("--watchdog", o->watchdog,
                "With --port/--sim: the board's watchdog period while serving, e.g. 500ms (default: the "
                "board's, 100 ms): the drives go off this long after the last frame")
      ->type_name("TIME");
  c->add_option("--level", o->level,
                "With --port/--sim: level every line with this height map (motionctl level probe -o FILE); "
                "$LEV=0 / $LEV=1 turn it off and on, $LEV reports it")
      ->type_name("FILE");
  c->callback([o] { run_serve(*o); });
}

}  // namespace mc::host::cli
