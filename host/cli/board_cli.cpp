#include "host/cli/board_cli.hpp"
#include "host/link/board_state.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "host/base/errors.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/limits.hpp"

namespace mc::host::cli {

GlobalOptions& global_options() {
  static GlobalOptions g;
  return g;
}

void add_global_options(CLI::App& app) {
  GlobalOptions& g = global_options();
  app.add_option("--port", g.port, "Serial port of the board, e.g. /dev/ttyUSB1 (board commands)")
      ->type_name("DEV");
  app.add_flag("--sim", g.sim,
               "Talk to the virtual board: connects to the running 'motionctl sim serve', or starts one in "
               "the background");
  app.add_option("--config", g.config, "Machine TOML for the virtual board and units (default: built-in)")
      ->type_name("FILE");
}

mc::machine::MachineConfig machine() {
  return mc::machine::machine_or_default(global_options().config);
}

namespace {

std::string absolute(const std::string& path) {
  if (path.empty() || path[0] == '/') return path;
  char cwd[4096];
  if (!::getcwd(cwd, sizeof cwd)) return path;
  return std::string(cwd) + "/" + path;
}

bool alive(long pid) {
  return pid > 0 && (::kill(pid_t(pid), 0) == 0 || errno == EPERM);
}

// An exclusive lock on sim.lock while finding or starting the server, so
// that two motionctl started at once do not start two servers.
class StateLock {
 public:
  StateLock() {
    fd_ = ::open((sim_state_dir() + "/sim.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (fd_ >= 0) ::flock(fd_, LOCK_EX);
  }
  ~StateLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  StateLock(const StateLock&) = delete;
  StateLock& operator=(const StateLock&) = delete;

 private:
  int fd_ = -1;
};

std::optional<SimServer> read_state() {
  std::ifstream f(sim_state_path());
  SimServer s;
  if (!f || !std::getline(f, s.pty) || !(f >> s.pid)) return std::nullopt;
  f.ignore(1);
  std::getline(f, s.config);
  return s;
}

// The first "motionctl: error: " line the log got after byte `from`, without the prefix.
std::string error_in_log(const std::string& log, std::streamoff from) {
  std::ifstream f(log, std::ios::binary);
  if (!f || !f.seekg(from)) return "";
  constexpr std::string_view kError = "motionctl: error: ";
  for (std::string line; std::getline(f, line);)
    if (line.rfind(kError, 0) == 0) return line.substr(kError.size());
  return "";
}

std::streamoff file_size(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  return f ? std::streamoff(f.tellg()) : 0;
}

SimServer start_sim_server(const std::string& config) {
  const std::string log = sim_state_dir() + "/sim.log";
  const std::streamoff log_start = file_size(log);
  const pid_t child = ::fork();
  if (child < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (child == 0) {
    // Detach: a new session, and a grandchild that init adopts, so that the
    // server outlives this command and is not in its terminal's job.
    ::setsid();
    if (::fork() != 0) ::_exit(0);
    const int null = ::open("/dev/null", O_RDONLY);
    const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    if (null >= 0) ::dup2(null, 0);
    if (out >= 0) {
      ::dup2(out, 1);
      ::dup2(out, 2);
    }
    const std::string idle = std::to_string(kSimIdleExitMin);
    std::vector<std::string> args = {"motionctl", "sim", "serve", "--idle-exit", idle};
    if (!config.empty()) {
      args.insert(args.begin() + 1, {"--config", config});
    }
    std::vector<char*> argv;
    argv.reserve(args.size() + 1);
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  ::waitpid(child, nullptr, 0);
  // The server registers itself once its PTY is open; an error it prints
  // in the log instead ends the wait at once.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < until) {
    if (auto s = find_sim_server()) return *s;
    const std::string err = error_in_log(log, log_start);
    if (!err.empty()) {
      std::string msg = "the virtual board did not start: " + err;
      msg += " (" + log + ")";
      throw std::runtime_error(msg);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  throw std::runtime_error("the virtual board did not start within 20 s (see " + log + ")");
}

}  // namespace

std::string sim_state_dir() {
  const char* xdg = std::getenv("XDG_RUNTIME_DIR");
  std::string dir =
      (xdg && *xdg) ? std::string(xdg) + "/motionctl" : "/tmp/motionctl-" + std::to_string(::getuid());
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST)
    throw std::runtime_error("cannot create " + dir + ": " + std::strerror(errno));
  return dir;
}

std::string sim_state_path() {
  return sim_state_dir() + "/sim.state";
}

std::optional<SimServer> find_sim_server() {
  auto s = read_state();
  if (!s || !alive(s->pid) || ::access(s->pty.c_str(), F_OK) != 0) return std::nullopt;
  return s;
}

// No lock here: ensure_sim_server holds it while it waits for this.
bool register_sim_server(const SimServer& s) {
  if (auto other = find_sim_server(); other && other->pid != s.pid) return false;
  const std::string tmp = sim_state_path() + ".tmp" + std::to_string(s.pid);
  {
    std::ofstream f(tmp);
    f << s.pty << '\n' << s.pid << '\n' << s.config << '\n';
    if (!f) throw std::runtime_error("cannot write " + tmp);
  }
  if (::rename(tmp.c_str(), sim_state_path().c_str()) != 0)
    throw std::runtime_error("cannot write " + sim_state_path() + ": " + std::strerror(errno));
  return true;
}

void unregister_sim_server(const SimServer& s) {
  auto cur = read_state();
  if (cur && cur->pid == s.pid) ::unlink(sim_state_path().c_str());
}

SimServer ensure_sim_server(const std::string& config) {
  // A bad machine file is the user's error, said here with its line, not a
  // server that dies in the background.
  mc::machine::machine_or_default(config);
  const std::string want = absolute(config);
  StateLock lock;
  if (auto s = find_sim_server()) {
    if (!config.empty() && s->config != want)
      throw InputError("--config", quote(config),
                       "the machine of the running virtual board (pid " + std::to_string(s->pid) + ", " +
                           (s->config.empty() ? std::string("built-in default") : s->config) +
                           "), or stop it first with 'motionctl sim stop'");
    return *s;
  }
  return start_sim_server(want);
}

std::string sim_wheel_socket(const std::string& pty) {
  std::string name = pty;  // "/dev/pts/5" -> "wheel-dev-pts-5.sock"
  std::replace(name.begin(), name.end(), '/', '-');
  return sim_state_dir() + "/wheel" + name + ".sock";
}

Board open_board() {
  const GlobalOptions& g = global_options();
  if (g.sim && !g.port.empty())
    throw InputError("--port and --sim", quote(g.port), "one of them: a real board or the virtual one");
  if (!g.sim && g.port.empty())
    throw InputError("board", "none given",
                     "--port DEV (a real board) or --sim (the virtual board) before the command");
  Board b;
  if (g.sim) {
    const SimServer s = ensure_sim_server(g.config);
    b.where = "the virtual board (" + s.pty + ")";
    b.port = std::make_unique<SerialPort>(s.pty);
  } else {
    b.where = g.port;
    b.port = std::make_unique<SerialPort>(g.port);
  }
  b.link = std::make_unique<BoardLink>(*b.port);
  b.link->connect();
  mc::machine::setup_axes(*b.link, machine());
  // The machine's following-error limit holds whenever a command of ours
  // arms the drives: a runaway trips a fault instead of running on.
  mc::machine::arm_following_limits(*b.link, machine());
  return b;
}

int parse_axis(const std::string& name, const char* option) {
  if (name.size() == 1) {
    const char c = char(name[0] | 0x20);
    if (c >= 'x' && c <= 'z') return c - 'x';
  }
  throw InputError(option, quote(name), "an axis name: x, y or z");
}

const char* axis_name(int axis) {
  static const char* const names[] = {"x", "y", "z"};
  return names[axis];
}

std::array<double, 3> axis_scales() {
  std::array<double, 3> s{};
  const mc::machine::MachineConfig m = machine();
  for (size_t a = 0; a < m.axes.size() && a < 3; ++a) s[a] = mc::machine::counts_per_m(m.axes[a]);
  return s;
}

void note(const std::string& s) {
  std::cerr << "motionctl: note: " << s << '\n';
}

int board_axis(BoardLink& l, const std::string& name) {
  const int a = parse_axis(name);
  const int naxes = read_naxes(l);
  if (a >= naxes)
    throw InputError("--axis", quote(name), "one of the board's " + std::to_string(naxes) + " axes");
  return a;
}

}  // namespace mc::host::cli
