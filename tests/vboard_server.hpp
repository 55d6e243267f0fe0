// The virtual board for CLI tests: a private runtime directory (so --sim
// finds only the test's own server) and `motionctl sim serve --fast` as a
// process of its own.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_run.hpp"

namespace mc::test {

// A private runtime directory, so that --sim finds only this test's server.
class PrivateRuntimeDir {
 public:
  PrivateRuntimeDir() {
    char tmpl[] = "/tmp/motionctl-test-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    ::setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1);
  }
  ~PrivateRuntimeDir() {
    try {
      run({"sim", "stop"});
      std::system(("rm -rf '" + dir_ + "'").c_str());
    } catch (...) {  // a destructor must not throw; the directory stays behind
    }
  }

 private:
  std::string dir_;
};

// `motionctl sim serve --fast` in its own process; the PTY path from its
// first line. With watch_status, its status lines (stderr) are kept for
// wait_dormant(); they come every second of wall time (the dormant one at
// once), so the pipe holds minutes of them while nobody reads.
class Server {
 public:
  // paced: the board paced to the wall clock (`--speed 1`), for a test that
  // measures the host's own timing in board time.
  explicit Server(bool watch_status = false, bool paced = false) {
    int out[2], err[2] = {-1, -1};
    if (::pipe(out) != 0 || (watch_status && ::pipe(err) != 0)) throw std::runtime_error("pipe");
    // MC_VBOARD_ENGINE=rtl (tests/vboard.cmake sets it for a second run of
    // the system tests): the same tests on the Verilated board.
    // Free-running, but waiting for the CLI's next request after each answer:
    // on a loaded machine a CLI's reaction time would otherwise become tens
    // of milliseconds of board time.
    std::vector<std::string> args = {"sim", "serve", "--no-register"};
    if (!paced) args.insert(args.end(), {"--fast", "--host-wait", "20ms"});
    if (const char* e = std::getenv("MC_VBOARD_ENGINE")) args.insert(args.end(), {"--engine", e});
    if (watch_status) args.insert(args.end(), {"--status-every", "1s"});
    pid_ = spawn(args, out[1], err[1]);
    if (pid_ <= 0) throw std::runtime_error("no server");
    ::close(out[1]);
    if (watch_status) {
      ::close(err[1]);
      status_fd_ = err[0];
    }
    char c;
    while (::read(out[0], &c, 1) == 1 && c != '\n') pty_ += c;
    ::close(out[0]);
  }
  ~Server() {
    if (status_fd_ >= 0) ::close(status_fd_);
    if (pid_ <= 0) return;  // kill(-1) would signal every process we own
    ::kill(pid_, SIGTERM);
    ::waitpid(pid_, nullptr, 0);
  }
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;
  const std::string& pty() const { return pty_; }
  // Waits until the server reports the board dormant: the link quiet for
  // longer than any watchdog period, every drive off, every axis at rest.
  // False when its board clock passes max_board_s first, or it exits.
  bool wait_dormant(double max_board_s) {
    if (status_fd_ < 0) throw std::logic_error("Server: constructed without watch_status");
    for (;;) {
      const size_t nl = status_.find('\n');
      if (nl == std::string::npos) {
        if (!read_until(status_fd_, "\n", status_)) return false;
        continue;
      }
      const std::string line = status_.substr(0, nl);
      status_.erase(0, nl + 1);
      if (line.find("clock stopped") != std::string::npos) return true;
      const size_t at = line.find(": board ");
      if (at != std::string::npos && std::stod(line.substr(at + 8)) > max_board_s) return false;
    }
  }
  // Stops it; true when it exited cleanly.
  bool stop() {
    if (pid_ <= 0) return false;
    ::kill(pid_, SIGTERM);
    int st = 0;
    ::waitpid(pid_, &st, 0);
    pid_ = -1;
    return WIFEXITED(st) && WEXITSTATUS(st) == 0;
  }

 private:
  pid_t pid_ = -1;
  int status_fd_ = -1;
  std::string pty_, status_;
};

}  // namespace mc::test
