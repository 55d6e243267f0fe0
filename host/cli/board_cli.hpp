// What the board commands of motionctl share: the global options (--port,
// --sim, --config, given before the command), opening the link to the real
// or the virtual board, finding or starting the background virtual board
// for --sim, and axis names.
//
// --sim: the virtual board must outlive one motionctl run (gains set in one
// run are there in the next), so it runs as its own process, `motionctl sim
// serve`, registered in a per-user state file (sim_state_dir()/sim.state:
// PTY path, pid, config). --sim connects to the registered server when it is
// alive, and otherwise starts one detached in the background, logging to
// sim.log next to the state file; that one exits after kSimIdleExitMin
// minutes without host traffic.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>

#include "host/link/board_link.hpp"
#include "host/link/serial_port.hpp"
#include "host/machine/machine_config.hpp"

namespace CLI {
class App;
}

namespace mc::host::cli {

struct GlobalOptions {
  std::string port;    // --port DEV
  bool sim = false;    // --sim
  std::string config;  // --config F (machine TOML; empty: the built-in default)
};
GlobalOptions& global_options();
void add_global_options(CLI::App& app);

// The machine (--config, or the built-in default).
mc::machine::MachineConfig machine();

// An open, connected link (PING + ID checked).
struct Board {
  std::unique_ptr<SerialPort> port;
  std::unique_ptr<BoardLink> link;
  std::string where;  // "/dev/ttyUSB1", "the virtual board (/dev/pts/5)"
};
// From the global options; throws InputError when neither --port nor --sim
// is given (or both).
Board open_board();

// --- the background virtual board ------------------------------------------
constexpr double kSimIdleExitMin = 10;
struct SimServer {
  std::string pty;
  long pid = 0;
  std::string config;  // absolute path, empty for the built-in machine
};
// $XDG_RUNTIME_DIR/motionctl, else /tmp/motionctl-UID; created 0700.
std::string sim_state_dir();
std::string sim_state_path();
// The registered server, if its process is alive and its PTY exists.
std::optional<SimServer> find_sim_server();
// Registers `s` unless a live server is registered already; returns whether it did.
bool register_sim_server(const SimServer& s);
// Removes the registration if it is s's.
void unregister_sim_server(const SimServer& s);
// The running server, or a freshly started one for `config`.
SimServer ensure_sim_server(const std::string& config);
// The handwheel socket of the server on pseudo-terminal `pty`
// (sim/vboard/wheel_socket.hpp), beside the state file: named after the
// terminal, so that a server started with --no-register has one too.
std::string sim_wheel_socket(const std::string& pty);

// Counts per metre of each board axis the machine config describes (0: none).
std::array<double, 3> axis_scales();
// "motionctl: note: ..." on stderr.
void note(const std::string& s);

// "x", "Y" -> 0, 1; throws InputError naming the option.
int parse_axis(const std::string& name, const char* option = "--axis");
const char* axis_name(int axis);
// parse_axis, and an axis the board has (it reports how many).
int board_axis(BoardLink& l, const std::string& name);

}  // namespace mc::host::cli
