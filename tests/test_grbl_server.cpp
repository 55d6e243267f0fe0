// The server of `motionctl serve` (host/grbl/server.hpp) on a real
// pseudo-terminal and a real TCP socket: a sender opens the symlink as a
// serial port, another connects over TCP, both get every reply. The test
// steps the server itself (one thread) until the replies it waits for arrive.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "host/grbl/server.hpp"
#include "tests/grbl_rig.hpp"

namespace fs = std::filesystem;

namespace mc::grbl::test {
namespace {

struct Fd {
  int fd = -1;
  explicit Fd(int f) : fd(f) {}
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
};

void write_all(int fd, const std::string& s) {
  ASSERT_EQ(::write(fd, s.data(), s.size()), ssize_t(s.size()));
}

// Steps the server until `fd` has delivered text containing `needle` (at most
// `rounds` rounds of the server loop).
std::string read_until(Server& server, DryRunBackend& backend, int fd, const std::string& needle,
                       int rounds = 2000) {
  std::string got;
  char buf[512];
  for (int i = 0; i < rounds && got.find(needle) == std::string::npos; ++i) {
    server.step([&] { backend.advance(1e-3); });
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) got.append(buf, size_t(n));
  }
  return got;
}

TEST(GrblServer, SpeaksGrblOnThePtyAndOnTcp) {
  const fs::path link = fs::temp_directory_path() / ("mc_grbl_pty_" + std::to_string(::getpid()));
  Rig rig;
  Server server(*rig.engine, ServerOptions{link.string(), 0, 1});
  ASSERT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(fs::read_symlink(link).string(), server.pty_path());
  ASSERT_GT(server.tcp_port(), 0);

  // The sender's side of the serial port, raw as a sender opens it.
  Fd serial(::open(link.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK));
  ASSERT_GE(serial.fd, 0);
  termios tio{};
  ::tcgetattr(serial.fd, &tio);
  ::cfmakeraw(&tio);
  ::tcsetattr(serial.fd, TCSANOW, &tio);

  Fd tcp(::socket(AF_INET, SOCK_STREAM, 0));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(server.tcp_port()));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(tcp.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ::fcntl(tcp.fd, F_SETFL, O_NONBLOCK);
  for (int i = 0; i < 100 && server.tcp_clients() == 0; ++i) server.step({});
  ASSERT_EQ(server.tcp_clients(), 1u);

  // Each sender is greeted with the banner when it connects, as by a board
  // that resets when its port opens.
  const std::string banner = "\r\nGrbl 1.1h ['$' for help]\r\n";
  EXPECT_EQ(read_until(server, rig.backend, serial.fd, "help]\r\n"), banner);
  EXPECT_EQ(read_until(server, rig.backend, tcp.fd, "help]\r\n"), banner);

  // A line from the serial port: its answer reaches both.
  write_all(serial.fd, "$I\n");
  const std::string want = "[VER:1.1h.20190830:]\r\n[OPT:VNM,4,128]\r\nok\r\n";
  EXPECT_EQ(read_until(server, rig.backend, serial.fd, "ok\r\n"), want);
  EXPECT_EQ(read_until(server, rig.backend, tcp.fd, "ok\r\n"), want);

  // A move and a status query over TCP; the move runs to its end.
  write_all(tcp.fd, "G1X2F1200\n");
  EXPECT_EQ(read_until(server, rig.backend, tcp.fd, "ok\r\n"), "ok\r\n");
  write_all(tcp.fd, "?");
  const std::string rep = read_until(server, rig.backend, tcp.fd, ">\r\n");
  EXPECT_EQ(rep.rfind("<Run|MPos:", 0), 0u) << rep;
  read_until(server, rig.backend, serial.fd, ">\r\n");
  for (int i = 0; i < 1000 && !rig.backend.drained(); ++i) server.step([&] { rig.backend.advance(1e-3); });
  EXPECT_EQ(rig.backend.status().position, (gcode::Vec3{2, 0, 0}));

  // A soft reset from the serial port; the TCP client sees the banner too.
  write_all(serial.fd, "\x18");
  EXPECT_EQ(read_until(server, rig.backend, tcp.fd, "help]\r\n"), banner);

  // A client that hangs up is dropped; the server goes on.
  ::close(tcp.fd);
  tcp.fd = -1;
  for (int i = 0; i < 100 && server.tcp_clients() > 0; ++i) server.step({});
  EXPECT_EQ(server.tcp_clients(), 0u);
  read_until(server, rig.backend, serial.fd, "help]\r\n");
  write_all(serial.fd, "$G\n");
  EXPECT_NE(read_until(server, rig.backend, serial.fd, "ok\r\n").find("[GC:"), std::string::npos);

  // The serial sender leaves replies unread and goes; the next one sees only its greeting.
  write_all(serial.fd, "$#\n");
  for (int i = 0; i < 20; ++i) server.step({});
  ::close(serial.fd);
  serial.fd = ::open(link.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(serial.fd, 0);
  EXPECT_EQ(read_until(server, rig.backend, serial.fd, "help]\r\n"), banner);
}

TEST(GrblServer, TheLinkIsRemovedAndNeverReplacesAFile) {
  const fs::path link = fs::temp_directory_path() / ("mc_grbl_link_" + std::to_string(::getpid()));
  Rig rig;
  {
    Server s(*rig.engine, ServerOptions{link.string(), -1, 1});
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(s.tcp_port(), -1);
  }
  EXPECT_FALSE(fs::exists(fs::symlink_status(link)));
  // A stale symlink (a server that was killed) is replaced.
  fs::create_symlink("/dev/pts/nonexistent", link);
  { Server s(*rig.engine, ServerOptions{link.string(), -1, 1}); }
  EXPECT_FALSE(fs::exists(fs::symlink_status(link)));
  // A regular file is not.
  { std::ofstream(link.string()) << "mine"; }
  try {
    Server s(*rig.engine, ServerOptions{link.string(), -1, 1});
    ADD_FAILURE() << "replaced a regular file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a symlink"), std::string::npos) << e.what();
  }
  fs::remove(link);
}

}  // namespace
}  // namespace mc::grbl::test
