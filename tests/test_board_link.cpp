// The host link against the virtual board over a real pseudo-terminal:
// retransmission loses and duplicates nothing under injected byte errors
// (the board's own counters and a register readback say so). And against a
// pseudo-terminal that nobody serves, or that only babbles: a clear error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <random>
#include <thread>

#include "host/control/board_gains.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/link/protocol.hpp"
#include "host/link/serial_port.hpp"
#include "host/motion/board_run.hpp"
#include "host/motion/interp_plan.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;
namespace bb = board::bits;
using host::BoardLink;
using host::LinkError;

// The virtual board served on a PTY from a thread, unpaced.
class ServedBoard {
 public:
  ServedBoard() : board_(machine::default_machine()) {
    sim::ServeOptions o;
    o.paced = false;
    thread_ = std::thread([this, o] { sim::serve(board_, pty_, o, stop_); });
  }
  ~ServedBoard() {
    stop_ = true;
    thread_.join();
  }
  const std::string& path() const { return pty_.path(); }

 private:
  sim::VirtualBoard board_;
  sim::Pty pty_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(BoardLink, InjectedByteErrorsLoseAndDuplicateNothing) {
  ServedBoard vb;
  host::SerialPort port(vb.path());
  host::FaultInjector faulty(port, 1e-3, 1e-3, 5);
  BoardLink link(faulty);
  link.connect();
  // Retries may hold the link up longer than the default watchdog period.
  link.write(br::WDOG, (1u << 24) - 1);

  std::mt19937 rng(3);
  const uint16_t regs[] = {br::IP_SET_X, br::IP_SET_Y, br::IP_SET_Z, br::HW_CFG};
  for (int i = 0; i < 300; ++i) {
    const uint16_t r = regs[rng() % 4];
    const uint32_t v = uint32_t(rng()) & (r == br::HW_CFG ? 0x1FFu : 0xFFFFFFFFu);
    link.write(r, v);
    ASSERT_EQ(link.read(r), v) << "write " << i;
  }

  // Segments: a duplicate would queue one twice, a loss one less; the
  // interpolator's completed count tells. They run only while armed.
  const uint32_t segs0 = link.read(br::IP_SEGS);
  link.write(br::CTRL, 1u << bb::C_ARM);
  int sent = 0;
  for (int frame = 0; frame < 40; ++frame) {
    std::vector<seg::Words> batch;
    const int n = 1 + int(rng() % 6);
    batch.reserve(size_t(n));
    for (int k = 0; k < n; ++k) batch.push_back(seg::pack(host::plan_dwell({0, 0, 0}, 20e-6).seg));
    // A full queue refuses the frame; the dwells drain it in board time,
    // and each try is a round trip of board time too.
    int tries = 1;
    while (!link.segments(batch))
      ASSERT_LT(++tries, 1000) << "the queue never drained (frame " << frame << ")";
    sent += n;
  }
  for (int i = 0; i < 2000 && ((link.read(br::IP_SEGS) - segs0) & 0xFFFF) < uint32_t(sent); ++i) {
  }
  EXPECT_EQ((link.read(br::IP_SEGS) - segs0) & 0xFFFF, uint32_t(sent));
  EXPECT_EQ(link.read(br::FAULT), 0u);

  // The errors really happened, and the link recovered from them.
  EXPECT_GT(faulty.flipped() + faulty.dropped(), 10u);
  EXPECT_GT(link.counters().retransmits, 0u);
  const uint32_t crc = link.read(br::LINK_CRC), junk = link.read(br::LINK_JUNK);
  EXPECT_GT((crc & 0xFFFF) + (crc >> 16) + junk, 0u) << "the board saw no bad frame";
  // Retransmissions of applied frames were answered DUP, not applied. (A
  // DUP reply can itself be lost, so the board may count more than the host saw.)
  const uint32_t board_dups = link.read(br::LINK_CMD) >> 16;
  EXPECT_GE(board_dups, link.counters().dups);
  EXPECT_LE(board_dups, link.counters().retransmits);
}

host::LinkOptions quick() {
  host::LinkOptions o;
  o.max_tries = 3;
  o.first_timeout = std::chrono::milliseconds(20);
  return o;
}

// What the host wrote to a pseudo-terminal nobody serves, as frames.
std::vector<host::proto::Frame> written(const sim::Pty& pty) {
  host::proto::Decoder dec;
  std::vector<host::proto::Frame> frames;
  uint8_t buf[256];
  for (ssize_t n; (n = ::read(pty.master_fd(), buf, sizeof buf)) > 0;)
    dec.push(host::proto::Bytes(buf, buf + n), frames);
  return frames;
}

TEST(BoardLink, SilentDeviceGivesUpAfterTheTries) {
  sim::Pty pty;  // nobody on the other side
  host::SerialPort port(pty.path());
  BoardLink link(port, quick());
  try {
    link.read(br::ID);
    FAIL() << "no error";
  } catch (const LinkError& e) {
    EXPECT_EQ(std::string(e.what()),
              "board at " + pty.path() + " does not answer after 3 tries (READ 0x0100 (ID))");
  }
  // Three tries of the very same frame: retransmitted, not renumbered.
  const std::vector<host::proto::Frame> f = written(pty);
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[1], f[0]);
  EXPECT_EQ(f[2], f[0]);
}

TEST(BoardLink, GarbageIsReportedAsGarbage) {
  sim::Pty pty;
  host::SerialPort port(pty.path());
  // A babbling device: bytes, but never a SYNC.
  std::mt19937 rng(1);
  std::vector<uint8_t> noise(1024);
  for (uint8_t& b : noise) b = uint8_t(rng() % 0xA0);
  ASSERT_EQ(::write(pty.master_fd(), noise.data(), noise.size()), ssize_t(noise.size()));
  BoardLink link(port, quick());
  try {
    link.connect();
    FAIL() << "no error";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("device at " + pty.path() + " answers garbage (1024 bytes"),
              std::string::npos)
        << e.what();
  }
}

TEST(SerialPort, AbsentAndBusyPortsSaySo) {
  try {
    host::SerialPort p("/dev/ttyUSB_motionctl_absent");
    FAIL();
  } catch (const LinkError& e) {
    EXPECT_STREQ(e.what(), "no such port /dev/ttyUSB_motionctl_absent");
  }
  sim::Pty pty;
  host::SerialPort first(pty.path());
  try {
    host::SerialPort second(pty.path());
    FAIL();
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("busy"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mc::test
