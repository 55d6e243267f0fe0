// The board twin's build parameters, as the two bitstreams set them: the
// servo board (make synth: loops, no step generators) and the stepper board
// (make synth-stepper: a step generator on every axis, no loops). INFO says
// which is which, and the stepper board refuses a PID enable. Frames go in
// and out on the twin's UART pins, as a host's would.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "hls/board_regs.hpp"
#include "hls/motioncore_icebreaker.hpp"
#include "hls/pid_regs.hpp"
#include "host/link/protocol.hpp"
#include "sim/vboard/uart_model.hpp"

namespace mc::test {
namespace {

namespace bp = board::proto;
namespace br = board::reg;
namespace hp = host::proto;

constexpr long kClkHz = 12'000'000, kBaud = 1'000'000;
constexpr int kCpb = sim::uart_clocks_per_bit(kClkHz, kBaud);

template <int STEPPERS, bool SERVO>
class TwinHost {
 public:
  TwinHost() { clock(64); }  // power-on reset and the PID's state clear

  uint32_t read(uint16_t addr) { return transact(hp::read(seq_.next(), addr)); }
  void write(uint16_t addr, uint32_t v) { transact(hp::write(seq_.next(), addr, v)); }

 private:
  uint32_t transact(const hp::Frame& req) {
    tx_.send(hp::encode(req));
    for (long i = 0; i < 200L * 10 * kCpb; ++i) {
      clock(1);
      while (rx_.has_byte()) {
        hp::Frame f;
        if (!dec_.push(rx_.take(), f) || hp::is_telemetry(f)) continue;
        const hp::Reply r = hp::parse_reply(f);
        EXPECT_EQ(r.status, bp::ST_OK) << "register 0x" << std::hex << int(req.payload[0]);
        return r.value;
      }
    }
    ADD_FAILURE() << "no reply";
    return 0;
  }
  void clock(long n) {
    for (long i = 0; i < n; ++i) {
      pins_.rx = tx_.pin();
      b_.step(pins_);
      rx_.clock(b_.tx());
      tx_.clock();
    }
  }

  MotioncoreIcebreaker<3, kClkHz, kBaud, true, STEPPERS, SERVO> b_;
  IcebreakerPins pins_;
  sim::UartSender tx_{kCpb};
  sim::UartReceiver rx_{kCpb};
  hp::Decoder dec_;
  hp::SeqGen seq_{1};
};

// INFO's build fields, written out rather than from info_word().
constexpr uint32_t kInfoBase = 3u | 9u << 4 | uint32_t(bp::VERSION) << 8 | 1u << 20;

TEST(BoardBuilds, ServoBoardRunsItsLoops) {
  TwinHost<0, true> h;
  EXPECT_EQ(h.read(br::INFO), kInfoBase | 1u << 19);
  h.write(pid_reg::addr(1, pid_reg::CTRL), 1);
  EXPECT_EQ(h.read(pid_reg::addr(1, pid_reg::CTRL)), 1u);
}

TEST(BoardBuilds, StepperBoardHasNoLoopToEnable) {
  TwinHost<7, false> h;
  EXPECT_EQ(h.read(br::INFO), kInfoBase | 7u << 16);
  h.write(pid_reg::addr(1, pid_reg::KP), 0x12345);
  h.write(pid_reg::addr(1, pid_reg::CTRL), 1);
  EXPECT_EQ(h.read(pid_reg::addr(1, pid_reg::CTRL)), 0u) << "no loop to enable";
  EXPECT_EQ(h.read(pid_reg::addr(1, pid_reg::KP)), 0x12345u) << "the gains still read back";
}

}  // namespace
}  // namespace mc::test
