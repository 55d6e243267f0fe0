// motionctl sim serve | stop | wheel: the virtual board
// (sim/virtual_board.hpp) on a pseudo-terminal, in the foreground; stopping
// the registered one; turning its handwheel (sim soak: cmd_soak.cpp).
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "sim/vboard/virtual_board.hpp"
#include "sim/vboard/wheel_socket.hpp"

namespace mc::host::cli {
namespace {

// How long `sim stop` waits for the server to go after each signal.
constexpr double kStopWaitS = 10;

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

extern "C" void on_stop_signal(int) {
  g_stop.store(true);
}

struct ServeOptions {
  bool fast = false;
  std::string speed = "1";
  std::string engine = "twin";
  std::string idle_exit = "0";
  std::string status_every = "5";
  std::string host_wait = "0";
  bool no_register = false;
  std::string config;  // overrides the global --config
};

// --speed: 1 (paced to the wall clock) or max (free-running); true: paced.
bool parse_speed(const std::string& s) {
  if (s == "1") return true;
  if (s == "max") return false;
  throw InputError("--speed", "'" + s + "'", "1 (paced to the wall clock) or max (free-running)");
}

void install_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGHUP, SIG_IGN);
  signal(SIGPIPE, SIG_IGN);
}

void serve(const ServeOptions& o) {
  const double idle_min = parse_number(o.idle_exit, "--idle-exit");
  const double every = parse_duration(o.status_every, "--status-every");
  if (idle_min < 0) throw InputError("--idle-exit", o.idle_exit, "minutes >= 0 (0: never)");
  if (!o.config.empty()) global_options().config = o.config;
  const bool paced = !o.fast && parse_speed(o.speed);
  const mc::sim::BoardEngine engine = mc::sim::parse_board_engine(o.engine, "--engine");
  const mc::machine::MachineConfig m = machine();
  mc::sim::VirtualBoard board(m, 0, engine);
  mc::sim::Pty pty;
  mc::sim::WheelSocket wheel(sim_wheel_socket(pty.path()));
  SimServer me{pty.path(), long(::getpid()), m.source == "built-in default" ? "" : global_options().config};
  if (!me.config.empty() && me.config[0] != '/') {
    char cwd[4096];
    if (::getcwd(cwd, sizeof cwd)) me.config = std::string(cwd) + "/" + me.config;
  }
  install_handlers();
  const bool registered = !o.no_register && register_sim_server(me);
  // The one line tools read: the PTY path.
  std::cout << pty.path() << std::endl;
  std::cerr << "motionctl sim: virtual board (" << m.source << ", " << board.configured_axes()
            << " plant axes, " << mc::sim::board_engine_name(engine) << " engine) on " << pty.path()
            << (paced ? ", paced to the wall clock" : ", free-running")
            << (registered ? ", registered for --sim" : "") << "; Ctrl-C stops it" << std::endl;

  mc::sim::ServeOptions so;
  so.paced = paced;
  so.host_wait_s = o.host_wait == "0" ? 0.0 : parse_duration(o.host_wait, "--host-wait");
  if (so.host_wait_s < 0 || so.host_wait_s > 1)
    throw InputError("--host-wait", o.host_wait, "a time from 0 to 1 s");
  so.idle_exit_s = idle_min * 60;
  so.status_every_s = every;
  so.wheel = &wheel;
  so.status = [paced](const mc::sim::ServeStatus& s) {
    char line[256];
    if (s.dormant) {
      std::snprintf(line, sizeof line,
                    "motionctl sim: board %.3f s: link quiet, drives off, axes at rest: clock stopped until "
                    "the host sends",
                    s.board_s);
    } else {
      std::snprintf(line, sizeof line,
                    "motionctl sim: board %.3f s, wall %.1f s, real-time factor %.3f%s, host bytes in %llu "
                    "out %llu dropped %llu",
                    s.board_s, s.wall_s, s.rt_factor, s.model_bound ? " (model-bound: running flat out)" : "",
                    static_cast<unsigned long long>(s.bytes_in), static_cast<unsigned long long>(s.bytes_out),
                    static_cast<unsigned long long>(s.bytes_dropped));
    }
    std::cerr << line;
    // Paced: the periods late so far, to see when they came.
    if (paced && !s.dormant) std::cerr << ", " << s.late_periods << " of " << s.periods << " periods late";
    std::cerr << std::endl;
  };
  const mc::sim::ServeStatus end = mc::sim::serve(board, pty, so, g_stop);
  if (registered) unregister_sim_server(me);
  std::cerr << "motionctl sim: stopped at board time " << end.board_s << " s"
            << (g_stop.load() ? "" : " (idle limit)") << std::endl;
  std::cerr << "motionctl sim: " << mc::sim::describe_speed(end, paced) << std::endl;
}

// Gone: no such process, or a zombie its parent has not reaped yet.
bool gone(long pid) {
  if (::kill(pid_t(pid), 0) != 0 && errno == ESRCH) return true;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return true;
  const size_t paren = line.rfind(')');
  return paren != std::string::npos && paren + 2 < line.size() && line[paren + 2] == 'Z';
}

// Polls until the process is gone or `seconds` have passed; whether it went.
bool wait_gone(long pid, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!gone(pid)) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// Says what happened, truthfully: stopped on SIGTERM, killed after it
// ignored SIGTERM, or an error (exit 1) when even SIGKILL left it running.
void stop() {
  const auto s = find_sim_server();
  if (!s) {
    std::cout << "no virtual board registered in " << sim_state_dir() << '\n';
    return;
  }
  const std::string which = "the virtual board (pid " + std::to_string(s->pid) + ", " + s->pty + ")";
  if (::kill(pid_t(s->pid), SIGTERM) != 0 && errno != ESRCH)
    throw std::runtime_error("cannot signal " + which + ": " + std::strerror(errno));
  if (wait_gone(s->pid, kStopWaitS)) {
    unregister_sim_server(*s);  // it does so itself; not when it died another way
    std::cout << "stopped " << which << '\n';
    return;
  }
  ::kill(pid_t(s->pid), SIGKILL);
  if (!wait_gone(s->pid, kStopWaitS))
    throw std::runtime_error("could not stop " + which + ": still running after SIGTERM and SIGKILL");
  unregister_sim_server(*s);
  std::cout << "killed " << which << " with SIGKILL: it did not stop within " << kStopWaitS
            << " s of SIGTERM\n";
}

struct WheelOptions {
  std::string detents;
  std::string seconds = "1";
};

// The server to turn: the one on --port PTY, else the registered one (--sim
// too: a wheel is no reason to start a board).
std::string wheel_pty() {
  const GlobalOptions& g = global_options();
  if (!g.port.empty()) return g.port;
  if (auto s = find_sim_server()) return s->pty;
  throw InputError("virtual board", "none running (" + sim_state_dir() + ")",
                   "one started with 'motionctl sim serve' (or by a --sim command), or --port PTY of one");
}

void wheel(const WheelOptions& o) {
  const double d = parse_number(o.detents, "--detents");
  if (d != std::round(d) || std::fabs(d) > mc::sim::kMaxHandwheelDetents)
    throw InputError(
        "--detents", quote(o.detents),
        "a whole number of detents up to " + std::to_string(mc::sim::kMaxHandwheelDetents) + " either way");
  const double s = parse_duration(o.seconds, "--seconds", Zero::allow);
  const std::string pty = wheel_pty();
  const std::string path = sim_wheel_socket(pty);
  if (::access(path.c_str(), F_OK) != 0)
    throw InputError("virtual board", quote(pty), "a running 'motionctl sim serve' on it (no " + path + ")");
  mc::sim::request_wheel_turn(path, int(d), s);
  std::cout << "turned the handwheel " << int(d) << " detents ("
            << int(d) * mc::sim::kHandwheelCountsPerDetent << " quadrature counts) over " << format_number(s)
            << " s of board time\n";
}

}  // namespace

void add_sim_command(CLI::App& app) {
  CLI::App* sim = app.add_subcommand(
      "sim", "The virtual board: serve it on a pseudo-terminal, stop it, or soak its link");
  sim->require_subcommand(1);
  auto o = std::make_shared<ServeOptions>();
  CLI::App* srv = sim->add_subcommand(
      "serve", "Run the virtual board in the foreground; prints its pseudo-terminal's path on stdout");
  srv->footer(
      "The board (3 axes, handwheel) at the machine's clock: its twin (hls/, the default) or with --engine\n"
      "rtl the Verilated board top, clock by clock. A DC-motor plant per axis of\n"
      "the machine config (--config before the command, or the built-in one) on its encoder and H-bridge\n"
      "pins, and its UART bit by bit on a pseudo-terminal: 'motionctl --port PTY status' talks to it.\n"
      "--speed 1 paces it to the wall clock (at most 4 ms ahead of it; slower when the model is slower) and\n"
      "counts the 100 us periods finished late; --speed max runs free. On exit it prints the periods late\n"
      "or the speed reached (x real time). The board's watchdog runs on board time. Status lines go to\n"
      "stderr. SIGINT or SIGTERM stops it.");
  srv->add_option("--config", o->config, "Machine TOML (the same as the global --config)")->type_name("FILE");
  srv->add_option("--speed", o->speed, "1: paced to the wall clock (default); max: free-running")
      ->type_name("1|max");
  srv->add_flag("--fast", o->fast, "The same as --speed max");
  srv->add_option("--host-wait", o->host_wait,
                  "Free-running: after answering a request, wait up to this long for the host's next one "
                  "(default 0: never)")
      ->type_name("TIME");
  srv->add_option("--engine", o->engine, "twin: the board's C++ twin (default); rtl: the Verilated board")
      ->type_name("twin|rtl");
  srv->add_option("--idle-exit", o->idle_exit, "Exit after this many minutes without host bytes (0: never)")
      ->type_name("MIN");
  srv->add_option("--status-every", o->status_every, "Interval of the status lines (default 5s)")
      ->type_name("TIME");
  srv->add_flag("--no-register", o->no_register,
                "Do not register for --sim (by default the first live server is the one --sim uses)");
  srv->callback([o] { serve(*o); });
  CLI::App* st = sim->add_subcommand("stop", "Stop the virtual board that --sim uses");
  st->footer(
      "Sends SIGTERM and waits up to 10 s for the server to exit; if it has not, SIGKILL. Prints which,\n"
      "and exits 1 when the process is still running after both.");
  st->callback([] { stop(); });
  auto wo = std::make_shared<WheelOptions>();
  CLI::App* wh = sim->add_subcommand("wheel", "Turn the handwheel of the running virtual board");
  wh->footer(
      "A 100-PPR handwheel on the board's HW_A/HW_B pins: 4 quadrature counts a detent, the edges spread\n"
      "evenly over --seconds of board time from now. Returns once the turn is done. The board running\n"
      "(motionctl sim serve, or one a --sim command started) is the registered one, or the one on\n"
      "--port PTY given before the command. What a turn moves: motionctl mpg.");
  wh->add_option("--detents", wo->detents, "Detents to turn, signed (negative: backwards)")
      ->required()
      ->type_name("N");
  wh->add_option("--seconds", wo->seconds, "Board time the turn takes (default 1 s)")->type_name("TIME");
  wh->callback([wo] { wheel(*wo); });
  add_soak_command(*sim);
}

}  // namespace mc::host::cli
