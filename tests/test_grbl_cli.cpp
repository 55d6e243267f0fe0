// motionctl serve as a user runs it: its errors, and a live run over TCP that
// changes a setting, is stopped with SIGTERM, removes its symlink and leaves
// the setting in its settings file.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/cli_run.hpp"

namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path =
      fs::temp_directory_path() / ("mc_grbl_cli_" + std::to_string(::getpid()) + "_" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

// Reads from fd until `needle` has arrived (or the other end closed).
std::string read_until(int fd, const std::string& needle) {
  std::string got;
  char buf[256];
  while (got.find(needle) == std::string::npos) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) break;
    got.append(buf, size_t(n));
  }
  return got;
}

TEST(GrblCli, ErrorsAreOneLine) {
  TempDir d;
  mc::test::expect_one_error_line({"serve"}, "--pty/--tcp");
  // Refused before the board is touched (no virtual board is started).
  mc::test::expect_one_error_line({"--sim", "serve", "--pty", (d.path / "l").string(), "--watchdog", "5s"},
                                  "watchdog period = 5 s");
  mc::test::expect_one_error_line({"serve", "--pty", "/nonexistent/dir/link"}, "symlink");
  const std::string bad = (d.path / "bad.toml").string();
  std::ofstream(bad) << "[setings]\n";
  mc::test::expect_one_error_line({"serve", "--tcp", "0", "--settings", bad}, bad + ":1");
}

TEST(GrblCli, ServesUntilSigtermAndKeepsTheSettings) {
  TempDir d;
  const std::string link = (d.path / "motioncore").string(), settings = (d.path / "grbl.toml").string();
  int out[2];
  ASSERT_EQ(::pipe(out), 0);
  pid_t pid = mc::test::spawn({"serve", "--pty", link, "--tcp", "0", "--settings", settings}, out[1]);
  ::close(out[1]);
  // A failed assertion below must not leave the server running.
  struct Reaper {
    pid_t& pid;
    ~Reaper() {
      if (pid > 0) ::kill(pid, SIGKILL), ::waitpid(pid, nullptr, 0);
    }
  } reaper{pid};
  const std::string banner = read_until(out[0], "Ctrl-C stops.\n");
  ASSERT_NE(banner.find("serial: " + link + " -> /dev/pts/"), std::string::npos) << banner;
  EXPECT_TRUE(fs::is_symlink(link));
  const std::string tcp = "tcp:    127.0.0.1:";
  const size_t at = banner.find(tcp);
  ASSERT_NE(at, std::string::npos) << banner;
  const int port = std::stoi(banner.substr(at + tcp.size()));

  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  EXPECT_EQ(read_until(s, "help]\r\n"), "\r\nGrbl 1.1h ['$' for help]\r\n");
  const std::string cmd = "$110=1234\n";
  ASSERT_EQ(::write(s, cmd.data(), cmd.size()), ssize_t(cmd.size()));
  EXPECT_EQ(read_until(s, "\r\n"), "ok\r\n");
  ::close(s);

  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  pid = 0;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_NE(read_until(out[0], "\n").find("stopped after answering 1 lines"), std::string::npos);
  ::close(out[0]);
  EXPECT_FALSE(fs::exists(fs::symlink_status(link)));
  std::ifstream f(settings);
  std::stringstream text;
  text << f.rdbuf();
  EXPECT_NE(text.str().find("\"$110\" = 1234.0\n"), std::string::npos) << text.str();
}

}  // namespace
