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

// `motionctl sim serve --fast` in its own process; the PTY path from its first line.
class Server {
 public:
  Server() {
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error("pipe");
    // MC_VBOARD_ENGINE=rtl (tests/vboard.cmake sets it for a second run of
    // the system tests): the same tests on the Verilated board.
    // Free-running, but waiting for the CLI's next request after each answer:
    // on a loaded machine a CLI's reaction time would otherwise become tens
    // of milliseconds of board time.
    std::vector<std::string> args = {"sim", "serve", "--fast", "--host-wait", "20ms", "--no-register"};
    if (const char* e = std::getenv("MC_VBOARD_ENGINE")) args.insert(args.end(), {"--engine", e});
    pid_ = spawn(args, fds[1]);
    if (pid_ <= 0) throw std::runtime_error("no server");
    ::close(fds[1]);
    char c;
    while (::read(fds[0], &c, 1) == 1 && c != '\n') pty_ += c;
    ::close(fds[0]);
  }
  ~Server() {
    if (pid_ <= 0) return;  // kill(-1) would signal every process we own
    ::kill(pid_, SIGTERM);
    ::waitpid(pid_, nullptr, 0);
  }
  const std::string& pty() const { return pty_; }
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
  std::string pty_;
};

}  // namespace mc::test
