// Running the built motionctl as a user runs it, for the CLI tests: no shell
// in between, stdout and stderr captured, and the error contract (one line
// "motionctl: error: ...", non-zero exit) as a reusable check.
// MOTIONCTL_PATH is defined by the test target.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace mc::test {

struct Result {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp(std::FILE* f) {
  std::string s;
  std::rewind(f);
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  return s;
}

// Starts motionctl with args, no shell in between: arguments reach the
// program exactly as written here. stdout goes to out_fd (-1: inherited),
// stderr to err_fd (-1: /dev/null).
inline pid_t spawn(const std::vector<std::string>& args, int out_fd, int err_fd = -1) {
  std::vector<std::string> storage{MOTIONCTL_PATH};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(storage.size() + 1);
  for (auto& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (out_fd >= 0) posix_spawn_file_actions_adddup2(&fa, out_fd, 1);
  if (err_fd >= 0)
    posix_spawn_file_actions_adddup2(&fa, err_fd, 2);
  else
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("posix_spawn " + storage[0] + " failed");
  return pid;
}

// Output goes to temporary files, so a chatty child cannot fill a pipe and block.
inline Result run(const std::vector<std::string>& args) {
  using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;
  File out(std::tmpfile(), &std::fclose), err(std::tmpfile(), &std::fclose);
  if (!out || !err) throw std::runtime_error("tmpfile failed");
  const pid_t pid = spawn(args, fileno(out.get()), fileno(err.get()));
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) throw std::runtime_error("waitpid failed");
  Result r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(out.get());
  r.err = slurp(err.get());
  return r;
}

// Reads fd into `seen` until it holds `marker` (true) or the writer is gone
// (false): the tests wait on what a program says, not on the clock.
inline bool read_until(int fd, const std::string& marker, std::string& seen) {
  char buf[512];
  while (seen.find(marker) == std::string::npos) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) return false;  // EOF, or EIO from a terminal whose other side closed
    seen.append(buf, size_t(n));
  }
  return true;
}

// Everything left on fd, until the writer is gone.
inline std::string read_all(int fd) {
  std::string s;
  char buf[512];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) s.append(buf, size_t(n));
  return s;
}

inline int count_lines(const std::string& s) {
  int n = 0;
  for (const char c : s) n += c == '\n';
  return n;
}

inline void expect_one_error_line(const std::vector<std::string>& args, const std::string& mentions = "") {
  std::string cmd;
  for (const auto& a : args) cmd += " " + a;
  const Result r = run(args);
  EXPECT_NE(r.exit_code, 0) << cmd;
  EXPECT_EQ(r.out, "") << cmd;
  EXPECT_EQ(count_lines(r.err), 1) << cmd << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("motionctl: error: ", 0), 0u) << cmd << "\n" << r.err;
  if (!mentions.empty()) {
    EXPECT_NE(r.err.find(mentions), std::string::npos) << cmd << "\n" << r.err;
  }
}

// Runs a command that must succeed, with its arguments in the failure message.
inline void expect_ok(const std::vector<std::string>& args) {
  const Result r = run(args);
  std::string cmd;
  for (const auto& a : args) cmd += " " + a;
  ASSERT_EQ(r.exit_code, 0) << cmd << "\n" << r.err;
}

// A command's --json output (a failed command or bad JSON: a failure, and discarded).
inline nlohmann::json run_json(const std::vector<std::string>& args) {
  const Result r = run(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out, nullptr, false);
}

}  // namespace mc::test
