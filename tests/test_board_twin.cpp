// The twin of the whole board (hls/motioncore_icebreaker.hpp) against the
// Verilated board top (rtl/motioncore_icebreaker.v), at the pins: both get the
// same RX, encoder, limit, probe, e-stop, button and handwheel levels every
// clock, and their TX, LED, drive, spindle and coolant pins must agree every
// clock; the fault latches,
// the arm state, the executor's and the link's states and the register
// file's RAM are compared too, so that a mismatch shows where it starts.
//
// The traffic is random and seeded (the seed is printed): good frames of
// every command and register, reads and writes, in range and out, segments,
// telemetry, duplicates, bad CRCs, truncated and overlong frames, junk,
// breaks, stop-bit errors, glitches and baud skew on the line, watchdog
// expiry, the machine I/O's registers (latches, spindle, handwheel jog,
// stepper axes), and limits, probe, e-stop, button, encoder errors and the
// handwheel on the pins. A profile per test weights them. Both boards are
// built with a step generator on every axis (MC_VBOARD_STEPPERS), so the
// stepper and the H-bridge pins are both covered.
//
// Then the twin's fast-forward (idle_clocks/advance) against clock-by-clock
// stepping over random states, and the speed of the twin and of the
// Verilated board in the same run (printed, never asserted).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "Vmotioncore_icebreaker.h"
#include "Vmotioncore_icebreaker___024root.h"
#include "hls/motioncore_icebreaker.hpp"
#include "hls/pid_regs.hpp"
#include "host/link/protocol.hpp"
#include "interp_bench.hpp"
#include "sim/vboard/uart_model.hpp"
#include "vl_context.hpp"

namespace mc::test {
namespace {

namespace bp = board::proto;
namespace br = board::reg;
namespace bb = board::bits;
namespace hp = host::proto;

using Twin = MotioncoreIcebreaker<3, 12'000'000, 1'000'000, true, MC_VBOARD_STEPPERS>;
using Vtop = Vmotioncore_icebreaker;
constexpr long kClkHz = 12'000'000;
constexpr int kCpb = sim::uart_clocks_per_bit(kClkHz, 1'000'000);
constexpr uint32_t kByteTimeout = 12'000;  // BYTE_TIMEOUT_US at 12 MHz

// ---- stimulus ----------------------------------------------------------------

// The host's RX line as runs of a level; high when nothing is queued.
class RxLine {
 public:
  bool idle() const { return runs_.empty(); }
  // The level of this clock.
  bool next() {
    if (runs_.empty()) return true;
    const bool l = runs_.front().first;
    if (--runs_.front().second == 0) runs_.pop_front();
    return l;
  }
  // Up to max clocks of the current level at once (at least one); how many.
  uint32_t take(uint32_t max, bool& level) {
    if (runs_.empty()) {
      level = true;
      return max;
    }
    level = runs_.front().first;
    const uint32_t k = std::min(max, runs_.front().second);
    if ((runs_.front().second -= k) == 0) runs_.pop_front();
    return k;
  }
  void run(bool level, uint32_t clocks) {
    if (clocks > 0) runs_.emplace_back(level, clocks);
  }
  // An 8N1 byte with cpb clocks per bit; stop = false makes a framing error.
  void byte(uint8_t b, uint32_t cpb = kCpb, bool stop = true) {
    run(false, cpb);
    for (int i = 0; i < 8; ++i) run(b >> i & 1, cpb);
    run(stop, cpb);
  }
  void bytes(const hp::Bytes& bs) {
    for (uint8_t b : bs) byte(b);
  }

 private:
  std::deque<std::pair<bool, uint32_t>> runs_;
};

// How often each kind of traffic comes (weights), the pauses, and how busy the pins are.
struct Profile {
  const char* name;
  int good, arm, dup, crc, trunc, junk, overlong, brk, ferr, glitch, skew;
  uint32_t gap_max;  // clocks between actions, uniform 0..gap_max
  int long_gap;      // 1/N of the pauses outlast the byte timeout (and often the watchdog)
  int pin_rate;      // a limit, e-stop or button change per this many clocks, on average
  int enc_still;     // percent of encoder stretches that stand still
  int enc_bad;       // percent of encoder stretches with errors and glitches
  int seg_pct;       // percent of good frames that queue segments
  int seg_big_pct;   // percent of those with up to six segments (else one or two)
};

constexpr Profile kCommands{"commands", 80, 6, 6, 3, 2, 2, 1, 1, 1, 1, 1, 300, 150, 2'000'000, 60, 3, 8, 20};
constexpr Profile kLineErrors{"line errors", 30, 3,         8,  15, 12, 10, 5, 5, 5, 5, 5,
                              300,           40, 2'000'000, 60, 3,  8,  20};
constexpr Profile kFaults{"faults", 40, 30, 3, 3, 3, 2, 1, 1, 1, 1, 1, 1500, 4, 80'000, 40, 15, 8, 20};
// Segment frames, mostly of six, and duplicates, mostly disarmed: the queue fills.
constexpr Profile kQueue{"queue", 80, 1, 15, 1, 1, 1, 1, 1, 1, 1, 1, 300, 200, 2'000'000, 60, 3, 70, 80};

class Host {
 public:
  Host(uint64_t seed, const Profile& p) : rng_(seed), gen_(seed * 7 + 3), p_(p) {
    gen_.max_line = 200;
    gen_.max_radius = 150;
  }

  bool line() {
    if (line_.idle()) schedule();
    return line_.next();
  }
  bool queued() const { return !line_.idle(); }
  // Up to max clocks of one level at once: how many, and the level.
  uint32_t line(uint32_t max, bool& level) {
    if (line_.idle()) schedule();
    return line_.take(max, level);
  }
  // A PID sample period of hundreds of clocks, as a machine has (after
  // reset it is the shortest, and the PID never rests).
  // Armed, the PID on every axis with a proportional gain on a short
  // sample period, no following-error limits: the drives follow the
  // encoders.
  void servo() {
    const auto send = [this](const hp::Frame& f) {
      line_.bytes(hp::encode(f));
      line_.run(true, 1500);  // about a reply's time
    };
    send(hp::write(seq_++, br::WDOG, (1u << board::WDOG_W) - 1));
    send(hp::write(seq_++, br::FAULT, 0xFFFF));
    send(hp::write(seq_++, br::CTRL, 1u << bb::C_ARM));
    for (int a = 0; a < 3; ++a) {
      send(hp::write(seq_++, br::axis(a, br::AX_FERR), 0));
      send(hp::write(seq_++, pid_reg::addr(uint8_t(a), pid_reg::KP), 1u << 20 | 16u << 24));
      send(hp::write(seq_++, pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1));
    }
    send(hp::write(seq_++, pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), 300));
  }
  void slow_pid() {
    const uint32_t ts = irange(300, 3000);
    line_.run(true, 100);  // out of reset first
    line_.bytes(hp::encode(hp::write(seq_++, pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), ts)));
  }

 private:
  uint32_t irange(uint32_t a, uint32_t b) { return a + uint32_t(rng_() % (b - a + 1)); }
  bool chance(int n) { return rng_() % uint64_t(n) == 0; }

  void schedule() {
    const uint32_t gap = chance(p_.long_gap) ? irange(kByteTimeout, 4 * kByteTimeout) : irange(0, p_.gap_max);
    line_.run(true, gap);
    const int w[] = {p_.good,     p_.arm, p_.dup,  p_.crc,    p_.trunc, p_.junk,
                     p_.overlong, p_.brk, p_.ferr, p_.glitch, p_.skew};
    int total = 0;
    for (int x : w) total += x;
    int k = int(rng_() % uint64_t(total)), kind = 0;
    while (k >= w[kind]) k -= w[kind++];

    switch (kind) {
      case 0:  // a good frame
        last_ = hp::encode(frame());
        line_.bytes(last_);
        break;
      case 1: {  // clear the faults and arm, and make the drives move
        const auto then = [this](const hp::Frame& f) {
          line_.run(true, irange(500, 1500));  // about a reply's time
          last_ = hp::encode(f);
          line_.bytes(last_);
        };
        if (chance(2)) then(hp::write(seq_++, br::WDOG, irange(2000, 40'000)));  // a short watchdog
        if (chance(2)) then(hp::write(seq_++, br::SAFETY, bb::SAFETY_DEFAULT));
        if (chance(2))  // no following-error limits
          for (int x = 0; x < 3; ++x) then(hp::write(seq_++, br::axis(x, br::AX_FERR), 0));
        const int a = int(irange(0, 2));
        if (chance(4)) {  // a following error of exactly FERR, or one more: the trip's edge
          const int32_t v = int32_t(irange(0, 12)) - 6;
          then(hp::write(seq_++, br::IP_CTRL, 1u << bb::I_ABORT));
          then(hp::write(seq_++, uint16_t(br::IP_SET_X + a), uint32_t(v)));
          then(hp::write(seq_++, br::IP_CTRL, 1u << bb::I_SET));  // command v: FOLLOW v - POS
          then(hp::write(seq_++, br::axis(a, br::AX_FERR), uint32_t(std::abs(v)) - irange(0, 1)));
        }
        then(hp::write(seq_++, br::FAULT, 0xFFFF));
        then(hp::write(seq_++, br::CTRL, 1u << bb::C_ARM));
        if (chance(2)) {  // the host drives an axis
          then(hp::write(seq_++, br::axis(a, br::AX_DRV), 1u << bb::D_OVR | (uint32_t(rng_()) & 0xFFFF)));
        } else {  // the PID does, on a short sample period
          then(hp::write(seq_++, br::axis(a, br::AX_DRV), 0));
          then(hp::write(seq_++, pid_reg::addr(uint8_t(a), pid_reg::KP), coef()));
          then(hp::write(seq_++, pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1));
          then(hp::write(seq_++, pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), irange(100, 3000)));
        }
        if (chance(3))  // stepper axes, open or closed loop, and the segments the generators step
          then(hp::write(seq_++, br::STEP_CFG,
                         value(br::STEP_CFG) & ~(chance(2) ? 0u : 7u << bb::SC_CLOSED_LSB)));
        if (chance(3)) {  // the machine I/O: latches on the probe or home switches, spindle, handwheel jog
          then(hp::write(seq_++, br::LATCH, value(br::LATCH)));
          for (int x = 0; x < 3; ++x) then(hp::write(seq_++, br::axis(x, br::AX_IDX), 1u << bb::X_ARM));
          then(hp::write(seq_++, br::IO_CTRL, value(br::IO_CTRL)));
          then(hp::write(seq_++, br::MPG, value(br::MPG) | 1u << bb::M_ON));
        }
        if (chance(5))
          then(hp::write(seq_++, br::axis(a, br::AX_FERR), irange(1, 60)));  // a tight following-error limit
        if (chance(3)) then(hp::write(seq_++, br::TLM, irange(2, 30) | irange(0, 7) << bb::T_AXES_LSB));
        break;
      }
      case 2:  // the same frame again: a duplicate; after a PING, a new frame
        if (last_.empty()) last_ = hp::encode(frame());
        if (chance(3)) {
          line_.bytes(hp::encode(hp::ping(seq_++)));
          line_.run(true, irange(500, 1500));
        }
        line_.bytes(last_);
        break;
      case 3: {  // a byte changed after SYNC: a bad CRC (or, in LEN, other framing)
        hp::Bytes b = hp::encode(frame());
        b[1 + rng_() % (b.size() - 1)] ^= uint8_t(1u << (rng_() % 8));
        line_.bytes(b);
        break;
      }
      case 4: {  // cut short; the rest never comes, or the next frame does
        hp::Bytes b = hp::encode(frame());
        b.resize(1 + rng_() % (b.size() - 1));
        line_.bytes(b);
        if (chance(2)) line_.run(true, kByteTimeout + irange(0, 2000));
        break;
      }
      case 5:  // junk, now and then with a SYNC in it
        for (uint32_t i = irange(1, 12); i > 0; --i) line_.byte(chance(8) ? bp::SYNC : uint8_t(rng_()));
        break;
      case 6:  // LEN above MAX_LEN
        line_.bytes({bp::SYNC, uint8_t(irange(bp::MAX_LEN + 1, 255)), uint8_t(rng_()), uint8_t(rng_())});
        break;
      case 7:  // a break: the line low for 10 to 40 bit times
        line_.run(false, irange(10 * kCpb, 40 * kCpb));
        break;
      case 8:  // a low stop bit, inside a frame or between frames
        line_.byte(uint8_t(rng_()), kCpb, false);
        if (chance(2)) line_.bytes(hp::encode(frame()));
        break;
      case 9:  // a glitch: a low pulse shorter than a bit
        line_.run(false, irange(1, kCpb - 1));
        break;
      default: {  // a frame at a skewed baud rate (one clock more or less per bit)
        const uint32_t cpb = chance(2) ? kCpb - 1 : kCpb + 1;
        for (uint8_t b : hp::encode(frame())) line_.byte(b, cpb);
        break;
      }
    }
  }

  // A random request: every command, register and value class.
  hp::Frame frame() {
    if (int(irange(0, 99)) < p_.seg_pct) {
      std::vector<seg::Words> segs;
      for (uint32_t n = int(irange(0, 99)) < p_.seg_big_pct ? irange(1, 6) : irange(1, 2); n > 0; --n) {
        const PlannedSegment g = chance(3) ? gen_.arc(at_) : gen_.line(at_);
        at_ = g.end;
        segs.push_back(seg::pack(g.seg));
        if (chance(20))
          for (uint32_t& x : segs.back()) x = uint32_t(rng_());  // garbage the core must take as it comes
      }
      return hp::segments(seq_++, segs);
    }
    const uint32_t k = irange(0, 99);
    if (k < 5) return hp::ping(seq_++);
    if (k < 40) return hp::read(seq_++, chance(3) ? addr() : known_addr());
    if (k < 90) {
      const uint16_t a = addr();
      return hp::write(seq_++, a, value(a));
    }
    hp::Frame f;
    f.seq = seq_++;
    if (k < 95) {  // a known command with the wrong length
      f.cmd = uint8_t(irange(0, 3));
      f.payload.resize(f.cmd == bp::CMD_SEG ? irange(1, 241) : irange(0, 9));
    } else {  // an unknown command
      f.cmd = uint8_t(irange(4, 255));
      f.payload.resize(irange(0, 8));
    }
    for (uint8_t& b : f.payload) b = uint8_t(rng_());
    return f;
  }

  // A register that exists: from the table, PID's or the board's.
  uint16_t known_addr() {
    if (chance(5)) return pid_reg::addr(uint8_t(irange(0, 2)), uint8_t(irange(0, pid_reg::NREGS_RAM)));
    const board::RegDef& d = board::REGS[irange(0, uint32_t(board::REGS.size()) - 1)];
    return d.per_axis ? br::axis(int(irange(0, 2)), d.addr) : d.addr;
  }

  uint16_t addr() {
    switch (irange(0, 9)) {
      case 0:
      case 1:
      case 2:
      case 3:
        return uint16_t(br::ID + irange(0, 0x1F));  // the globals, and a few past them
      case 4:
      case 5:
      case 6:
        return br::axis(int(irange(0, 3)),
                        uint16_t(irange(0, 11)));  // axis 3 and offsets 10, 11 do not exist
      case 7:
        return pid_reg::addr(uint8_t(irange(0, 3)), uint8_t(irange(0, 15)));
      case 8:
        return pid_reg::addr(pid_reg::GLOBAL_AXIS, uint8_t(irange(0, 3)));
      default:
        return uint16_t(rng_());
    }
  }

  uint32_t coef() { return irange(1, 1u << 22) | irange(10, 30) << 24; }

  uint32_t value(uint16_t a) {
    const uint32_t any = uint32_t(rng_());
    if (a >> 8 == 0) {                       // PID
      if ((a >> 4) == pid_reg::GLOBAL_AXIS)  // Ts: now and then the shortest
        return chance(8) ? any : chance(8) ? irange(60, 200) : irange(200, 3000);
      switch (a & 0xF) {
        case pid_reg::CTRL:
          return irange(0, 3);
        case pid_reg::OLIM:
        case pid_reg::ILIM:
          return chance(2) ? 0 : irange(0, 40000);
        case pid_reg::DBAND:
          return chance(2) ? 0 : irange(0, 8);
        case pid_reg::ELIM:
          return chance(2) ? 0 : irange(10, 500);
        default:
          return chance(8) ? any : coef();
      }
    }
    if (a >= br::AXIS_BASE) {
      switch (a & 0xF) {
        case br::AX_ENC_CFG:
          return irange(0, 20) | irange(0, 3) << bb::E_DIR_INV;
        case br::AX_IDX:
          return irange(0, 3);
        case br::AX_ENC_STAT:
          return irange(0, 1);
        case br::AX_DRV:
          return (chance(2) ? 1u << bb::D_OVR : 0) | (any & 0xFFFF);
        case br::AX_FERR:
          return chance(3) ? 0 : chance(2) ? irange(1, 300) : any;
        default:
          return chance(2) ? irange(0, 2000) - 1000 : any;
      }
    }
    switch (a) {
      case br::CTRL:
        return (chance(4) ? 0 : 1u << bb::C_ARM) | (chance(8) ? 1u << bb::C_IP_HOLD : 0);
      case br::FAULT:
        return chance(3) ? any : 0xFFFF;
      case br::WDOG:
        return chance(2) ? irange(300, 20'000) : chance(2) ? irange(20'000, 400'000) : any;
      case br::SAFETY:
        return chance(4) ? any & 0xFF : bb::SAFETY_DEFAULT;
      case br::TLM:
        return (chance(2) ? 0 : chance(4) ? irange(1, 4) : irange(5, 60)) | irange(0, 7) << bb::T_AXES_LSB;
      case br::IP_CTRL:
        return irange(0, 7);
      case br::HW_CFG:
        return irange(0, 0x3FF);
      case br::IO_CTRL:
        return chance(3) ? any : irange(0, 0x1F) | irange(0, 0x3FF) << bb::IO_DUTY_LSB;
      case br::LATCH:  // each axis: none, index, home switch or probe; probe polarity; stop on a latch
        return irange(0, 0x3F) << bb::L_SRC_LSB | irange(0, 1) << bb::L_PROBE_INV |
               irange(0, 1) << bb::L_STOP;
      case br::MPG:  // on, axis, step, one-count detents, a short rate
        return (chance(4) ? 0 : 1u << bb::M_ON) | irange(0, 3) << bb::M_AXIS_LSB |
               irange(0, 3) << bb::M_STEP_LSB | irange(0, 1) << bb::M_DETENT1 |
               irange(0, 40) << bb::M_RATE_LSB;
      case br::MPG_INC:
        return chance(4) ? any : irange(0, 300);
      case br::STEP_CFG:  // steppers, closed loop, short pulses and setups, inversions
        return chance(8) ? any
                         : irange(0, 7) << bb::SC_STEPPER_LSB | irange(0, 7) << bb::SC_CLOSED_LSB |
                               irange(0, 6) << bb::SC_PW_LSB | irange(0, 6) << bb::SC_SETUP_LSB |
                               irange(0, 7) << bb::SC_STEP_INV_LSB | irange(0, 7) << bb::SC_DIR_INV_LSB;
      default:
        return chance(2) ? irange(0, 2000) - 1000 : any;
    }
  }

  std::mt19937_64 rng_;
  SegGen gen_;
  Profile p_;
  RxLine line_;
  hp::Bytes last_;
  host::Vec3 at_{0, 0, 0};
  uint8_t seq_ = 1;
};

// Encoders, switches, button and handwheel.
// The encoder pins that show a count (count mod 4; A leads B counting up).
constexpr bool kQuadA[4] = {false, true, true, false}, kQuadB[4] = {false, false, true, true};

class PinGen {
 public:
  PinGen(uint64_t seed, const Profile& p) : rng_(seed), p_(p) {}

  void clock(IcebreakerPins& p) {
    for (int a = 0; a < 3; ++a) {
      Axis& x = ax_[a];
      if (x.left-- == 0) {  // a new stretch: still, slow, fast, or with errors
        x.left = 2000 + uint32_t(rng_() % 60'000);
        x.period = int(rng_() % 100) < p_.enc_still ? 0 : rng_() % 3 ? 2 + uint32_t(rng_() % 400) : 1;
        x.dir = rng_() % 2 ? 1 : -1;
        x.bad = int(rng_() % 100) < p_.enc_bad;
      }
      if (x.period != 0 && ++x.t >= x.period) {
        x.t = 0;
        x.count += x.bad && rng_() % 10 == 0 ? 2 * x.dir : x.dir;  // two edges at once: an error
      }
      p.enc_a[a] = kQuadA[x.count & 3];
      p.enc_b[a] = kQuadB[x.count & 3];
      if (x.bad && rng_() % 3000 == 0) p.enc_a[a] = !p.enc_a[a];  // a one-clock glitch
    }
    // The probe: touches now and then, with bounce.
    if (rng_() % uint64_t(p_.pin_rate) == 0) probe_left_ = 200 + uint32_t(rng_() % 20'000);
    if (probe_left_ > 0) {
      --probe_left_;
      p.probe = probe_left_ > 0 && (probe_left_ > 40 || rng_() % 2);
    }
    // Switches: now and then one trips, and is released after a while.
    if (rng_() % uint64_t(p_.pin_rate) == 0) {
      const int k = int(rng_() % 5);
      bool& s = k < 3 ? p.lim[k] : k == 3 ? p.estop : p.btn_n;
      s = !s;
      release_ = 100 + uint32_t(rng_() % 30'000);
    }
    if (rng_() % 200'000 == 0) hw_fast_ = !hw_fast_;  // a handwheel turned fast for a while
    if (release_ > 0 && --release_ == 0) {
      for (bool& l : p.lim) l = false;
      p.estop = false;
      p.btn_n = true;
    }
    if (rng_() % (hw_fast_ ? 40 : 700) == 0) {
      hw_ += rng_() % 2 ? 1 : -1;
      p.hw_a = hw_ & 1 ? !(hw_ & 2) : (hw_ & 2);
      p.hw_b = hw_ & 2;
    }
  }

 private:
  struct Axis {
    int64_t count = 0;
    uint32_t left = 0, period = 0, t = 0;
    int dir = 1;
    bool bad = false;
  };
  std::mt19937_64 rng_;
  Profile p_;
  Axis ax_[3];
  uint32_t release_ = 0, probe_left_ = 0;
  int64_t hw_ = 0;
  bool hw_fast_ = false;
};

// ---- the two boards ------------------------------------------------------------

void apply_pins(Vtop& t, const IcebreakerPins& p) {
  t.RX = p.rx;
  t.BTN_N = p.btn_n;
  t.ESTOP = p.estop;
  t.PROBE = p.probe;
  t.X_ENC_A = p.enc_a[0];
  t.X_ENC_B = p.enc_b[0];
  t.Y_ENC_A = p.enc_a[1];
  t.Y_ENC_B = p.enc_b[1];
  t.Z_ENC_A = p.enc_a[2];
  t.Z_ENC_B = p.enc_b[2];
  t.X_LIM = p.lim[0];
  t.Y_LIM = p.lim[1];
  t.Z_LIM = p.lim[2];
  t.HW_A = p.hw_a;
  t.HW_B = p.hw_b;
}

// What the twin did, from its pins and registers: the test's coverage.
struct Coverage {
  uint64_t clocks = 0, armed = 0, pwm_high = 0, tx_low = 0;
  uint64_t steps = 0, jogs = 0, latches = 0, io_stops = 0, spindle_on = 0;
  uint64_t replies[6] = {}, telemetry = 0, bad_tx = 0;
  uint16_t faults_seen = 0;
  uint32_t link_crc = 0, link_framing = 0, link_nak = 0, link_dup = 0, link_junk = 0, segs = 0;

  void print(const char* name, uint64_t seed) const {
    std::printf(
        "%s (seed %llu): %llu clocks; replies ok %llu dup %llu bad_reg %llu bad_len %llu bad_cmd %llu full "
        "%llu; telemetry %llu; board counters crc %u framing %u nak %u dup %u junk %u; segments %u; faults "
        "seen 0x%04x; armed %llu clocks, PWM high %llu; step pulses %llu, handwheel jogs %llu, latches %llu "
        "(%llu stopping), spindle on %llu clocks\n",
        name, (unsigned long long)seed, (unsigned long long)clocks, (unsigned long long)replies[0],
        (unsigned long long)replies[1], (unsigned long long)replies[2], (unsigned long long)replies[3],
        (unsigned long long)replies[4], (unsigned long long)replies[5], (unsigned long long)telemetry,
        link_crc, link_framing, link_nak, link_dup, link_junk, segs, faults_seen, (unsigned long long)armed,
        (unsigned long long)pwm_high, (unsigned long long)steps, (unsigned long long)jogs,
        (unsigned long long)latches, (unsigned long long)io_stops, (unsigned long long)spindle_on);
  }
};

class Watcher {
 public:
  void clock(const Twin& t, Coverage& c) {
    ++c.clocks;
    rx_.clock(t.tx());
    while (rx_.has_byte()) {
      hp::Frame f;
      if (!dec_.push(rx_.take(), f)) continue;
      if (hp::is_telemetry(f)) {
        ++c.telemetry;
      } else if (hp::is_reply(f) && f.payload.size() == bp::REPLY_LEN && f.payload[0] < 6) {
        ++c.replies[f.payload[0]];
      } else {
        ++c.bad_tx;
      }
    }
    const auto& b = t.u_board;
    c.armed += b.u_safety.armed_o;
    c.faults_seen |= b.u_safety.fault_o;
    for (int a = 0; a < 3; ++a) c.pwm_high += t.pwm(a);
    c.tx_low += !t.tx();
    for (int a = 0; a < 3; ++a)  // a STEP edge: the generator's pin rose at this edge
      c.steps += (b.u_step.stepper >> a & 1) && b.u_step.u_gen[a].step_o && !b.u_step.step_q[a];
    c.jogs += b.u_io.r.jog_o != 0;
    c.latches += b.u_io.r.latch_o != 0;
    c.io_stops += b.u_io.r.stop_o;
    c.spindle_on += t.sp_en();
  }
  static void counters(const Twin& t, Coverage& c) {
    const auto& sh = t.u_board.u_regs.shadow;
    const auto w = [&](uint16_t a) { return sh[Twin::Board::Regs::sidx(a)]; };
    c.link_crc = w(br::LINK_CRC) & 0xFFFF;
    c.link_framing = w(br::LINK_CRC) >> 16;
    c.link_nak = w(br::LINK_CMD) & 0xFFFF;
    c.link_dup = w(br::LINK_CMD) >> 16;
    c.link_junk = w(br::LINK_JUNK) & 0xFFFF;
    c.segs = uint32_t(t.u_board.u_core.interp().seg_cnt());
  }

 private:
  sim::UartReceiver rx_{kCpb};
  hp::Decoder dec_;
};

#define VL(name) (top_->rootp->motioncore_icebreaker__DOT__u_board__DOT__##name)

class Lockstep {
 public:
  explicit Lockstep(uint32_t seed) : ctx_(random_context(seed)), top_(std::make_unique<Vtop>(ctx_.get())) {
    apply_pins(*top_, pins_);
    top_->CLK = 0;
    top_->eval();
  }
  ~Lockstep() { top_->final(); }
  Lockstep(const Lockstep&) = delete;
  Lockstep& operator=(const Lockstep&) = delete;

  IcebreakerPins pins_;
  Twin twin_;

  void clock() {
    apply_pins(*top_, pins_);
    top_->CLK = 1;
    top_->eval();
    top_->CLK = 0;
    top_->eval();
    twin_.step(pins_);
    ++clocks_;
    compare();
  }
  uint64_t clocks() const { return clocks_; }
  int mismatches() const { return mismatches_; }
  // Sets the heartbeat counter of both boards (it has no other input).
  void set_heartbeat(uint32_t hb) {
    VL(hb) = hb;
    twin_.u_board.hb = hb;
  }

 private:
  void check(const char* what, uint64_t rtl, uint64_t twin) {
    if (rtl == twin) return;
    if (++mismatches_ <= 12)
      ADD_FAILURE() << "clock " << clocks_ << ": " << what << " rtl 0x" << std::hex << rtl << " twin 0x"
                    << twin;
  }

  void compare() {
    if (clocks_ < 2) return;  // the first edge brings the random power-up state in
    const Vtop& t = *top_;
    const Twin& w = twin_;
    check("TX", t.TX, w.tx());
    check("LEDR_N", t.LEDR_N, w.ledr_n());
    check("LEDG_N", t.LEDG_N, w.ledg_n());
    check("X_PWM", t.X_PWM, w.pwm(0));
    check("Y_PWM", t.Y_PWM, w.pwm(1));
    check("Z_PWM", t.Z_PWM, w.pwm(2));
    check("X_DIR", t.X_DIR, w.dir(0));
    check("Y_DIR", t.Y_DIR, w.dir(1));
    check("Z_DIR", t.Z_DIR, w.dir(2));
    check("DRV_EN", t.DRV_EN, w.drv_en());
    check("SP_PWM", t.SP_PWM, w.sp_pwm());
    check("SP_EN", t.SP_EN, w.sp_en());
    check("SP_DIR", t.SP_DIR, w.sp_dir());
    check("FLOOD", t.FLOOD, w.flood());
    if (clocks_ < 20) return;  // the power-on reset has run
    // Internal state, where a mismatch starts.
    const auto& b = w.u_board;
    const auto& r = b.u_regs.r;
    check("fault", VL(fault), b.u_safety.fault_o);
    check("armed", VL(armed), b.u_safety.armed_o);
    check("safety wd", VL(u_safety__DOT__wd), b.u_safety.wd);
    check("SAFETY", VL(safety), r.safety_o);
    check("WDOG", VL(wdog), r.wdog_o);
    check("uart_rx busy", VL(u_urx__DOT__busy), b.u_urx.busy);
    check("uart_tx busy", VL(u_utx__DOT__busy), b.u_utx.busy);
    check("link_rx st", VL(u_lrx__DOT__st), b.u_lrx.st);
    check("link_rx idle", VL(u_lrx__DOT__idle), b.u_lrx.idle);
    check("link_tx st", VL(u_ltx__DOT__st), b.u_ltx.st);
    check("regs xs", VL(u_regs__DOT__xs), r.xs);
    if (VL(u_regs__DOT__ra) == r.ra) check("regs q", VL(u_regs__DOT__q), r.q);
    check("regs cnt_pend", VL(u_regs__DOT__cnt_pend), r.cnt_pend);
    check("regs rep_pend", VL(u_regs__DOT__rep_pend), r.rep_pend);
    check("regs tlm_pend", VL(u_regs__DOT__tlm_pend), r.tlm_pend);
    check("regs tlm_seq", VL(u_regs__DOT__tlm_seq), r.tlm_seq);
    check("regs last_valid", VL(u_regs__DOT__last_valid), r.last_valid);
    if (r.last_valid) check("regs last_seq", VL(u_regs__DOT__last_seq), r.last_seq);
    check("regs w_act", VL(u_regs__DOT__w_act), r.w_act);
    check("regs sample_cnt", VL(u_regs__DOT__sample_cnt), r.sample_cnt);
    check("regs tlm_decim", VL(u_regs__DOT__tlm_decim), r.tlm_decim);
    check("regs tlm_left", VL(u_regs__DOT__tlm_left), r.tlm_left);
    check("drv_ovr", VL(drv_ovr), r.drv_ovr_o);
    check("hw_pos", VL(hw_pos), uint32_t(b.u_hw.out().pos));
    check("seg_count", VL(seg_count), uint32_t(b.u_core.interp().count()));
    check("io latch", VL(io_latch), b.u_io.r.latch_o);
    check("io stop", VL(io_stop), b.u_io.r.stop_o);
    check("io sw", VL(u_io__DOT__sw), b.u_io.r.sw);
    check("io pend", VL(u_io__DOT__pend), b.u_io.r.pend);
    check("io jog", VL(ip_jog), b.u_io.r.jog_o);
    check("stepper", VL(u_step__DOT__stepper), b.u_step.stepper);
    check("closed", VL(u_step__DOT__closed), b.u_step.closed);
#define STEP_GEN(a, f) VL(u_step__DOT__g_ax__BRA__##a##__KET____DOT__g_gen__DOT__##f)
#define CHECK_STEP(a)                                                                     \
  check("step backlog", STEP_GEN(a, u_gen__DOT__backlog_o), b.u_step.u_gen[a].backlog_o); \
  check("step last", STEP_GEN(a, u_gen__DOT__last), b.u_step.u_gen[a].last);              \
  check("step st", STEP_GEN(a, u_gen__DOT__st), b.u_step.u_gen[a].st);                    \
  check("step q", STEP_GEN(a, q), b.u_step.q[a]);                                         \
  check("step err", STEP_GEN(a, err_q), b.u_step.err_q[a]);                               \
  check("step ferr", STEP_GEN(a, fe), b.u_step.fe[a]);
    CHECK_STEP(0)
    CHECK_STEP(1)
    CHECK_STEP(2)
#undef CHECK_STEP
#undef STEP_GEN
#define CHECK_POS(a)                                                                     \
  check("cmd", VL(u_core__DOT__u_interp__DOT__g_pos__BRA__##a##__KET____DOT__p),         \
        uint32_t(b.u_core.interp().pos(a)));                                             \
  check("pos", VL(u_core__DOT____Vcellout__g_enc__BRA__##a##__KET____DOT__u_dec__pos_o), \
        uint32_t(b.u_core.decoder(a).pos()));
    CHECK_POS(0)
    CHECK_POS(1)
    CHECK_POS(2)
#undef CHECK_POS
    for (int a = 0; a < 3; ++a)
      check("drv_cmd", vl::get_bits(VL(drv_cmd), 16 * a, 16), uint16_t(b.u_core.drv_cmd(a)));
    if (clocks_ % 1024 == 0)
      for (int i = 0; i < 256; ++i) check("shadow RAM", VL(u_regs__DOT__shadow)[i], b.u_regs.shadow[i]);
  }

  uint64_t clocks_ = 0;
  int mismatches_ = 0;
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vtop> top_;
};

// One random run of the twin against the RTL.
Coverage random_run(const Profile& prof, uint64_t seed, uint64_t clocks) {
  Lockstep s{uint32_t(seed)};
  Host host(seed, prof);
  PinGen pins(seed ^ 0x9e3779b97f4a7c15ull, prof);
  Watcher watch;
  Coverage cov;
  s.pins_.rx = true;
  for (int i = 0; i < 64; ++i) s.clock();  // power-on reset and the PID's state clear
  for (uint64_t c = 0; c < clocks && s.mismatches() == 0; ++c) {
    s.pins_.rx = host.line();
    pins.clock(s.pins_);
    s.clock();
    watch.clock(s.twin_, cov);
  }
  Watcher::counters(s.twin_, cov);
  cov.print(prof.name, seed);

  EXPECT_EQ(s.mismatches(), 0) << prof.name << ", seed " << seed;
  EXPECT_EQ(cov.bad_tx, 0u) << "the board sent a frame that is neither a reply nor telemetry";
  return cov;
}

Coverage& operator+=(Coverage& a, const Coverage& b) {
  a.clocks += b.clocks;
  a.armed += b.armed;
  a.pwm_high += b.pwm_high;
  for (int i = 0; i < 6; ++i) a.replies[i] += b.replies[i];
  a.telemetry += b.telemetry;
  a.faults_seen = uint16_t(a.faults_seen | b.faults_seen);
  a.link_crc += b.link_crc;
  a.link_framing += b.link_framing;
  a.link_nak += b.link_nak;
  a.link_dup += b.link_dup;
  a.link_junk += b.link_junk;
  a.segs += b.segs;
  return a;
}

// Good frames of every command and register, telemetry, segments, duplicates.
TEST(BoardTwin, RandomCommandsMatchRtl) {
  Coverage c;
  for (uint64_t seed : {101, 102, 103}) c += random_run(kCommands, seed, 800'000);
  EXPECT_GT(c.replies[bp::ST_OK], 250u);
  EXPECT_GT(c.replies[bp::ST_DUP], 3u);
  EXPECT_GT(c.replies[bp::ST_BAD_REG], 100u);
  EXPECT_GT(c.replies[bp::ST_BAD_LEN], 5u);
  EXPECT_GT(c.replies[bp::ST_BAD_CMD], 3u);
  EXPECT_GT(c.telemetry, 30u);
  EXPECT_GT(c.segs, 10u);
  EXPECT_GT(c.pwm_high, 100'000u);
  EXPECT_TRUE(c.faults_seen >> bb::F_FERR_LSB & 7) << "no following-error trip";
}

// Bad frames and line errors: every drop counter counts.
TEST(BoardTwin, LineErrorsMatchRtl) {
  Coverage c;
  for (uint64_t seed : {201, 202}) c += random_run(kLineErrors, seed, 600'000);
  EXPECT_GT(c.link_crc, 30u);
  EXPECT_GT(c.link_framing, 40u);
  EXPECT_GT(c.link_junk, 500u);
  EXPECT_GT(c.link_dup, 3u);
  EXPECT_GT(c.replies[bp::ST_OK], 40u);
}

// Switches, encoder errors and the watchdog: every fault latches, clears and re-arms.
TEST(BoardTwin, FaultsMatchRtl) {
  Coverage c;
  for (uint64_t seed : {301, 302}) c += random_run(kFaults, seed, 800'000);
  for (int bit : {bb::F_WDOG, bb::F_ESTOP, bb::F_LIMIT_LSB, bb::F_LIMIT_LSB + 1, bb::F_LIMIT_LSB + 2,
                  bb::F_ENC_LSB, bb::F_ENC_LSB + 1, bb::F_ENC_LSB + 2})
    EXPECT_TRUE(c.faults_seen >> bit & 1) << "fault bit " << bit << " never seen";
  EXPECT_GT(c.armed, 100'000u);
}

// The segment queue fills: refused frames (FULL), duplicates of segment frames.
TEST(BoardTwin, QueueFullMatchesRtl) {
  const Coverage c = random_run(kQueue, 601, 700'000);
  EXPECT_GT(c.replies[bp::ST_FULL], 0u);
  EXPECT_GT(c.replies[bp::ST_DUP], 0u);
}

// The LEDs: the heartbeat's top bit takes 2^23 clocks to move, so the test
// sets both boards' heartbeat counters just short of it (and of the wrap).
TEST(BoardTwin, LedsMatchRtl) {
  for (uint32_t start : {(1u << 23) - 30'000, (1u << 24) - 30'000}) {
    Lockstep s{77};
    Host host(77, kFaults);
    PinGen pins(78, kFaults);
    for (int i = 0; i < 64; ++i) s.clock();
    s.set_heartbeat(start);
    bool ledg = s.twin_.ledg_n(), toggled = false;
    for (int c = 0; c < 60'000 && s.mismatches() == 0; ++c) {
      if (c > 40'000) {  // quiet, no fault, until the top bit has moved; then traffic and faults
        s.pins_.rx = host.line();
        pins.clock(s.pins_);
      }
      s.clock();
      toggled |= s.twin_.ledg_n() != ledg;
      ledg = s.twin_.ledg_n();
    }
    EXPECT_EQ(s.mismatches(), 0);
    EXPECT_TRUE(toggled) << "the green LED never changed";
  }
}

// ---- the fast-forward -----------------------------------------------------------

// The first difference between two twins' whole states, or "".
std::string state_diff(const Twin& x, const Twin& y) {
  std::string d;
  const auto same = [&d](const char* what, uint64_t a, uint64_t b) {
    if (d.empty() && a != b) d = std::string(what) + ": " + std::to_string(a) + " vs " + std::to_string(b);
  };
#define SAME(f) same(#f, uint64_t(x.f), uint64_t(y.f))
  SAME(por);
  SAME(s1);
  SAME(s2);
  const auto &bx = x.u_board, &by = y.u_board;
#define SAMEB(f) same(#f, uint64_t(bx.f), uint64_t(by.f))
  SAMEB(hb);
  SAMEB(u_urx.data_o);
  SAMEB(u_urx.valid_o);
  SAMEB(u_urx.ferr_o);
  SAMEB(u_urx.busy);
  SAMEB(u_urx.cnt);
  SAMEB(u_urx.bitn);
  SAMEB(u_urx.sh);
  SAMEB(u_utx.cnt);
  SAMEB(u_utx.left);
  SAMEB(u_utx.sh);
  SAMEB(u_utx.busy);
  SAMEB(u_utx.tx_o);
  SAMEB(u_lrx.frame_o);
  SAMEB(u_lrx.seq_o);
  SAMEB(u_lrx.cmd_o);
  SAMEB(u_lrx.len_o);
  SAMEB(u_lrx.pay_rdata_o);
  SAMEB(u_lrx.crc_err_o);
  SAMEB(u_lrx.framing_o);
  SAMEB(u_lrx.junk_o);
  SAMEB(u_lrx.st);
  SAMEB(u_lrx.idx);
  SAMEB(u_lrx.crc_lo);
  SAMEB(u_lrx.idle);
  SAMEB(u_lrx.u_crc.crc_o);
  SAMEB(u_lrx.u_crc.sh);
  SAMEB(u_lrx.u_crc.n);
  for (int i = 0; i < 256; ++i) SAMEB(u_lrx.pay[i]);
  for (int i = 0; i < 16; ++i) SAMEB(u_ltx.ram[i]);
  SAMEB(u_ltx.q);
  SAMEB(u_ltx.ra);
  SAMEB(u_ltx.st);
  SAMEB(u_ltx.hb);
  SAMEB(u_ltx.wleft);
  SAMEB(u_ltx.hold);
  SAMEB(u_ltx.byte_o);
  SAMEB(u_ltx.valid_o);
  SAMEB(u_ltx.u_crc.crc_o);
  SAMEB(u_ltx.u_crc.sh);
  SAMEB(u_ltx.u_crc.n);
  SAMEB(u_safety.wd);
  SAMEB(u_safety.enc_err_d);
  SAMEB(u_safety.fault_o);
  SAMEB(u_safety.armed_o);
  for (int i = 0; i < 256; ++i) SAMEB(u_regs.shadow[i]);
#define SAMER(f) SAMEB(u_regs.r.f)
  SAMER(drop_busy);
  SAMER(cnt_nak_inc);
  SAMER(cnt_dup_inc);
  SAMER(cnt_pend);
  SAMER(cu1);
  SAMER(cu2);
  SAMER(cu_c1);
  SAMER(cu_c2);
  SAMER(ra);
  SAMER(sa);
  SAMER(q);
  SAMER(sq);
  SAMER(q_smp);
  SAMER(sample_cnt);
  SAMER(addr);
  SAMER(data);
  SAMER(xs);
  SAMER(f_seq);
  SAMER(f_cmd);
  SAMER(f_len);
  SAMER(status);
  SAMER(bi);
  SAMER(rbi);
  SAMER(rv);
  SAMER(last_seq);
  SAMER(last_valid);
  SAMER(rep_pend);
  SAMER(rep_sending);
  SAMER(tlm_pend);
  SAMER(tlm_sending);
  SAMER(val_shadow);
  SAMER(val_direct);
  SAMER(set_n);
  SAMER(set_t1);
  SAMER(set_t2);
  SAMER(arm_set_o);
  SAMER(arm_clr_o);
  SAMER(fclr_o);
  SAMER(safety_o);
  SAMER(wdog_o);
  SAMER(ferr_o);
  SAMER(seg_wr_o);
  SAMER(ip_abort_o);
  SAMER(ip_hold_o);
  SAMER(ip_clr_o);
  for (int a = 0; a < 3; ++a) SAMER(enc_filt_o[a]);
  SAMER(enc_dir_inv_o);
  SAMER(enc_idx_clr_en_o);
  SAMER(enc_idx_arm_o);
  SAMER(enc_idx_disarm_o);
  SAMER(enc_err_clr_o);
  SAMER(drv_ovr_o);
  SAMER(drv_ovr_we_o);
  SAMER(hw_filt_o);
  SAMER(hw_dir_inv_o);
  SAMER(w_act);
  SAMER(w_hdr);
  SAMER(w_tlm);
  SAMER(w_tlm_busy);
  SAMER(w_end);
  SAMER(w_a);
  SAMER(w_k);
  SAMER(w_ptr);
  SAMER(done_d);
  SAMER(tlm_left);
  SAMER(tlm_decim);
  SAMER(tlm_axes);
  SAMER(tlm_due_l);
  SAMER(t1);
  SAMER(t2);
  SAMER(ta1);
  SAMER(ta2);
  SAMER(tlm_n);
  SAMER(tlm_seq);
  SAMER(tx_start_o);
  SAMER(tx_seq_o);
  SAMER(tx_cmd_o);
  SAMER(tx_status_en_o);
  SAMER(tx_status_o);
  SAMER(tx_wbase_o);
  SAMER(tx_nwords_o);
  // motion_core: what its interface shows, the sample RAM and the timers.
  const auto &cx = bx.u_core, &cy = by.u_core;
  const auto ox = cx.outputs(), oy = cy.outputs();
#define SAMEO(f) same(#f, uint64_t(ox.f), uint64_t(oy.f))
  SAMEO(pid_wready);
  SAMEO(pid_rvalid);
  SAMEO(pid_rdata);
  SAMEO(seg_count);
  SAMEO(ip_busy);
  SAMEO(ip_underrun);
  SAMEO(ip_ovf);
  SAMEO(ip_seg_cnt);
  SAMEO(tick);
  SAMEO(done);
  SAMEO(smp_rdata);
  for (int a = 0; a < 3; ++a) {
    same("decoder", cx.decoder(a) == cy.decoder(a), true);  // every register, not only its outputs
    SAMEO(pwm[a]);
    SAMEO(dir[a]);
    SAMEO(drv_en[a]);
    SAMEO(drv_u[a]);
    SAMEO(drv_cmd[a]);
    SAMEO(smp_sat[a]);
    SAMEO(pid_en[a]);
    SAMEO(pos[a]);
    SAMEO(cmd[a]);
    for (int f = 0; f < SMP_FIELDS; ++f)
      same("sample", uint32_t(cx.sample(a, SampleField(f))), uint32_t(cy.sample(a, SampleField(f))));
  }
  same("pwm count", cx.pwm_count(), cy.pwm_count());
  same("pid timer", cx.pid().timer(), cy.pid().timer());
  same("pid sweep", uint64_t(cx.pid().sweep_clock()), uint64_t(cy.pid().sweep_clock()));
  same("pid busy", cx.pid().busy(), cy.pid().busy());
  same("interp phase", cx.interp().phase(), cy.interp().phase());
  same("interp state", uint64_t(cx.interp().state()), uint64_t(cy.interp().state()));
  same("handwheel", bx.u_hw.out() == by.u_hw.out(), true);
  same("mc_io", bx.u_io == by.u_io, true);
  same("mc_step", bx.u_step == by.u_step, true);
#undef SAME
#undef SAMEB
#undef SAMER
#undef SAMEO
  return d;
}

bool same_pins(const Twin& x, const Twin& y) {
  bool ok = x.tx() == y.tx() && x.ledr_n() == y.ledr_n() && x.ledg_n() == y.ledg_n();
  for (int a = 0; a < 3; ++a) ok = ok && x.pwm(a) == y.pwm(a) && x.dir(a) == y.dir(a);
  return ok && x.drv_en() == y.drv_en() && x.sp_pwm() == y.sp_pwm() && x.sp_en() == y.sp_en() &&
         x.sp_dir() == y.sp_dir() && x.flood() == y.flood();
}

// Quiet stretches: long pauses on the line, encoders mostly still.
constexpr Profile kIdle{"idle", 80, 10, 5, 3, 12, 2, 1, 1, 1, 1, 1, 30'000, 6, 300'000, 85, 5, 8, 20};
// The same with the encoders mostly moving, no re-arming and the
// watchdog fed: for Host::servo().
constexpr Profile kServo{"servo", 80, 0, 5, 3, 12, 2, 1, 1, 1, 1, 1, 300, 1'000'000, 3'000'000, 10, 2, 8, 20};

// A host's traffic on a board with a machine's PID period and pins that
// move: the reference twin steps every clock, the fast one skips.
struct Rig {
  Rig(uint64_t seed, const Profile& traffic, const Profile& pin_traffic = kIdle)
      : rng(seed), host(seed, traffic), pins(seed + 1, pin_traffic) {
    host.slow_pid();
  }
  // Both twins clocked through what the host has queued (its frames reach
  // the board whole only so: a loop that takes a line level per skip
  // stretches their gaps past the byte timeout).
  void step_queued() {
    while (host.queued()) {
      p.rx = host.line();
      ref.step(p);
      fast.step(p);
    }
  }
  std::mt19937_64 rng;
  Host host;
  PinGen pins;
  Twin ref, fast;
  IcebreakerPins p;
};

// advance(n) over random states leaves exactly the state of n step()s: a twin
// that skips every idle stretch it can against one that steps every clock,
// the whole state compared after each skip, the pins every stepped clock and
// TX every clock (a byte goes out inside an advance).
TEST(BoardTwin, AdvanceEqualsSteps) {
  // tx_bits: TX edges inside advances; frames: advances in which link_tx
  // handed uart_tx a byte (two start bits or more); drive_changes: new PID
  // outputs taken inside
  uint64_t all_skips = 0, tx_bits = 0, frames = 0, drive_changes = 0, runs_ended = 0;
  // Then a host that talks more (replies go out inside advances), and the
  // three axes servoing on moving encoders (the PID's outputs are taken
  // inside advances).
  struct Run {
    uint64_t seed;
    const Profile& traffic;
    bool servo;
  };
  for (const Run& run : {Run{401, kIdle, false}, Run{402, kIdle, false}, Run{403, kIdle, false},
                         Run{404, kCommands, false}, Run{405, kServo, true}}) {
    const uint64_t seed = run.seed;
    Rig rig(seed, run.traffic, run.servo ? run.traffic : kIdle);
    if (run.servo) {
      rig.host.servo();
      rig.step_queued();
    }
    auto& [rng, host, pins, ref, fast, p] = rig;
    uint64_t clocks = 0, skipped = 0, skips = 0;
    while (clocks < 1'500'000) {
      p.rx = host.line();
      pins.clock(p);
      const uint32_t limit = 1 + uint32_t(rng() % (rng() % 2 ? 64 : 200'000));
      const uint32_t k = fast.idle_clocks(p, limit);
      ASSERT_LE(k, limit);
      if (k > 0) {
        const uint32_t n = rng() % 4 ? k : 1 + uint32_t(rng() % k);  // the whole stretch, or part of it
        // The drive over the stretch, and over a part of it from edge `from`.
        const uint32_t from = uint32_t(rng() % n), part = 1 + uint32_t(rng() % (n - from));
        // And runs of kk clocks from `from` at one PWM level (drive_runs).
        const uint32_t kk = 1 + uint32_t(rng() % 24), most = (n - from) / kk;
        int32_t drive[3], drive_part[3];
        uint32_t change[3], runs[3];
        for (int a = 0; a < 3; ++a) {
          drive[a] = fast.drive_in(a, 0, n);
          drive_part[a] = fast.drive_in(a, from, part);
          change[a] = fast.drive_change(a);
          runs[a] = fast.drive_runs(a, from, kk, most);
          ASSERT_LE(runs[a], most);
        }
        std::vector<int8_t> pins_after[3];  // the signed pin after each edge
        std::vector<bool> line;             // TX after each clock, as tx_levels() tells it
        fast.tx_levels(n, [&](bool level, uint32_t m) { line.insert(line.end(), m, level); });
        ASSERT_EQ(line.size(), n);
        int16_t cmd_before[3];
        for (int a = 0; a < 3; ++a) cmd_before[a] = ref.u_board.u_core.drv_cmd(a);
        fast.advance(p, n);
        int32_t stepped[3] = {}, stepped_part[3] = {};
        uint32_t starts = 0;  // start bits on TX
        for (uint32_t i = 0; i < n; ++i) {
          const bool tx = ref.tx();
          bool dir_before[3];
          for (int a = 0; a < 3; ++a) dir_before[a] = ref.dir(a);
          ref.step(p);
          for (int a = 0; a < 3; ++a) {
            const int32_t d = ref.pwm(a) ? (ref.dir(a) ? -1 : 1) : 0;
            pins_after[a].push_back(int8_t(d));
            stepped[a] += d;
            if (i >= from && i < from + part) stepped_part[a] += d;
            // Inside, DIR changes only at the edge drive_change() names.
            if (i > 0 && i != change[a]) {
              ASSERT_EQ(dir_before[a], ref.dir(a)) << "DIR of axis " << a << " at edge " << i << " of " << n;
            }
          }
          ASSERT_EQ(line[i], ref.tx()) << "TX after clock " << i + 1 << " of " << n << " at clock " << clocks;
          tx_bits += ref.tx() != tx;
          starts += tx && !ref.tx();
        }
        for (int a = 0; a < 3; ++a) {
          ASSERT_EQ(drive[a], stepped[a]) << "drive of axis " << a << " over " << n << " clocks";
          ASSERT_EQ(drive_part[a], stepped_part[a])
              << "drive of axis " << a << " over edges " << from << " + " << part << " of " << n;
          drive_changes += ref.u_board.u_core.drv_cmd(a) != cmd_before[a];
          // The runs at one level, and no more of them (unless the next
          // would straddle the change).
          const auto b = pins_after[a].begin() + from;
          ASSERT_TRUE(std::all_of(b, b + runs[a] * kk, [&](int8_t x) { return x == *b; })) << "axis " << a;
          const bool straddles = from < change[a] && from + (runs[a] + 1) * kk > change[a];
          if (runs[a] < most && !straddles) {
            ++runs_ended;
            ASSERT_FALSE(std::all_of(b, b + (runs[a] + 1) * kk, [&](int8_t x) { return x == *b; }))
                << "axis " << a << ": " << runs[a] << " runs of " << kk << ", and one more";
          }
        }
        frames += starts >= 2;
        clocks += n;
        skipped += n;
        ++skips;
        const std::string d = state_diff(ref, fast);
        ASSERT_EQ(d, "") << "after advancing " << n << " clocks at clock " << clocks << ", seed " << seed;
      } else {
        ref.step(p);
        fast.step(p);
        ++clocks;
        ASSERT_TRUE(same_pins(ref, fast)) << "clock " << clocks << ", seed " << seed;
      }
    }
    ASSERT_EQ(state_diff(ref, fast), "");
    std::printf("advance (seed %llu): %llu clocks, %llu of them in %llu advances\n", (unsigned long long)seed,
                (unsigned long long)clocks, (unsigned long long)skipped, (unsigned long long)skips);
    EXPECT_GT(skipped, clocks / 2) << "seed " << seed;
    all_skips += skips;
  }
  std::printf("advance: %llu TX edges, %llu byte hand-overs and %llu drive updates inside advances\n",
              (unsigned long long)tx_bits, (unsigned long long)frames, (unsigned long long)drive_changes);
  EXPECT_GT(all_skips, 3000u);
  EXPECT_GT(tx_bits, 100u);
  EXPECT_GT(frames, 3u);
  EXPECT_GT(drive_changes, 1000u);
  EXPECT_GT(runs_ended, 1000u);
}

// Encoder edges taken inside advances (Twin::foldable, the virtual board's
// jumps): a twin that advances over each idle stretch with the encoders'
// pins changing inside it, as many edges in a row as foldable() allows,
// against one that steps every clock with the pins changing at those
// clocks; the whole state compared after each advance. The three axes
// servo on their encoders and segments run, so that edges come inside
// stretches that take drive updates and move the command; now and then an
// edge skips a count (an error, which no stretch may take).
TEST(BoardTwin, AdvanceTakesEncoderEdges) {
  // Servoing, with pauses between frames and most frames queueing segments.
  static constexpr Profile kMoving{"moving", 80, 0,      5,         3,         12, 2, 1,  1, 1,
                                   1,        1,  20'000, 1'000'000, 3'000'000, 10, 2, 70, 60};
  uint64_t folded = 0, refused = 0, skips = 0, moved = 0;
  for (uint64_t seed : {411, 412, 413}) {
    Rig rig(seed, kMoving);
    rig.host.servo();
    rig.step_queued();
    auto& [rng, host, pins, ref, fast, p] = rig;
    // Each encoder's count (its pins show it), the clocks between its
    // edges (0: still), its direction and phase.
    int64_t count[3] = {};
    uint32_t period[3] = {}, phase[3] = {};
    int dir[3] = {1, 1, 1};
    const auto show = [&](int a, int64_t c) {
      count[a] = c;
      p.enc_a[a] = kQuadA[c & 3];
      p.enc_b[a] = kQuadB[c & 3];
    };
    uint64_t clocks = 0;
    while (clocks < 1'500'000) {
      // The host's line holds a level for `left` clocks (its frames reach
      // the board whole), the other pins too.
      bool level = true;
      uint32_t left = host.line(6000, level);
      p.rx = level;
      pins.clock(p);
      for (int a = 0; a < 3; ++a) show(a, count[a]);  // the encoders are this test's
      if (clocks == 0 || rng() % 300 == 0)
        for (int a = 0; a < 3; ++a) {
          period[a] = rng() % 4 == 0 ? 0 : 13 + uint32_t(rng() % 400);
          phase[a] = uint32_t(rng() % 1000);
          dir[a] = rng() % 2 ? 1 : -1;
        }
      while (left > 0) {
        const uint32_t k = fast.idle_clocks(p, left);
        if (k < 2) {
          ref.step(p);
          fast.step(p);
          ++clocks;
          --left;
          ASSERT_TRUE(same_pins(ref, fast)) << "clock " << clocks << ", seed " << seed;
          continue;
        }
        std::vector<mc::PinChange> ch;
        std::vector<int64_t> to;  // the count each change shows
        int64_t c[3] = {count[0], count[1], count[2]};
        for (uint32_t t = 1; t < k; ++t)
          for (int a = 0; a < 3; ++a)
            if (period[a] != 0 && (clocks + t + phase[a]) % period[a] == 0) {
              c[a] += rng() % 500 == 0 ? 2 * dir[a] : dir[a];
              ch.push_back(mc::PinChange{t, a, kQuadA[c[a] & 3], kQuadB[c[a] & 3], false});
              to.push_back(c[a]);
            }
        const size_t f = fast.foldable(ch.data(), ch.size());
        ASSERT_LE(f, ch.size());
        uint32_t n = f < ch.size() ? ch[f].clock : k;  // up to the first edge it cannot take
        if (rng() % 4 == 0) n = 1 + uint32_t(rng() % n);
        size_t take = 0;
        while (take < f && ch[take].clock < n) ++take;
        int32_t cmd[3];
        for (int a = 0; a < 3; ++a) cmd[a] = ref.u_board.u_core.interp().pos(a);
        fast.advance(p, n, ch.data(), take);
        size_t e = 0;
        for (uint32_t i = 0; i < n; ++i) {
          for (; e < take && ch[e].clock == i; ++e) show(ch[e].axis, to[e]);
          ref.step(p);
        }
        for (int a = 0; a < 3; ++a) moved += take > 0 && ref.u_board.u_core.interp().pos(a) != cmd[a];
        clocks += n;
        left -= n;
        folded += take;
        refused += f < ch.size();
        ++skips;
        ASSERT_EQ(state_diff(ref, fast), "") << "after advancing " << n << " clocks with " << take
                                             << " edges at clock " << clocks << ", seed " << seed;
      }
    }
  }
  std::printf(
      "edges: %llu taken inside %llu advances (%llu with the command moving), %llu stretches "
      "ended at one refused\n",
      (unsigned long long)folded, (unsigned long long)skips, (unsigned long long)moved,
      (unsigned long long)refused);
  EXPECT_GT(folded, 10'000u);
  EXPECT_GT(moved, 100u);
  EXPECT_GT(refused, 100u);
}

// The virtual board's host line ahead of time: pin_after(t) is pin() after t
// clock() calls, through the byte on the line, the queued ones and idle.
TEST(UartModel, PinAfterIsThePinThatManyClocksOn) {
  std::mt19937_64 rng(77);
  sim::UartSender tx(kCpb);
  uint64_t edges = 0;  // level changes seen: bytes, not an idle line, were checked
  for (int round = 0; round < 300; ++round) {
    if (rng() % 3 != 0)
      for (uint64_t i = 0, n = rng() % 4; i < n; ++i) tx.send(uint8_t(rng()));
    tx.clock_n(uint32_t(rng() % 200));
    sim::UartSender later = tx;
    for (uint32_t t = 0; t < 700; ++t) {
      ASSERT_EQ(tx.pin_after(t), later.pin()) << "t " << t << ", round " << round;
      const bool before = later.pin();
      later.clock();
      edges += later.pin() != before;
    }
  }
  EXPECT_GT(edges, 5'000u);
}

// advance_line(p, n, line) over the bits of a byte on RX leaves exactly the
// state of n step()s with the line's levels: a twin that runs every byte's
// data bits at once against one that steps every clock, over good and bad
// traffic (glitches, framing errors, breaks), the whole state compared after
// each stretch.
TEST(BoardTwin, LineAdvanceEqualsSteps) {
  for (uint64_t seed : {601, 602}) {
    Rig rig(seed, kLineErrors);
    auto& [rng, host, pins, ref, fast, p] = rig;
    std::deque<bool> ahead;  // the line's next levels, from the host's open-loop schedule
    const auto line = [&](uint32_t t) {
      while (ahead.size() <= t) ahead.push_back(host.line());
      return bool(ahead[t]);
    };
    uint64_t clocks = 0, in_bytes = 0, advances = 0;
    while (clocks < 1'500'000) {
      p.rx = line(0);
      const uint32_t limit = 1 + uint32_t(rng() % (rng() % 2 ? 40 : 2000));
      const uint32_t k = fast.line_clocks(p, limit, line);
      ASSERT_LE(k, limit);
      if (k > 0) {
        const uint32_t n = rng() % 4 ? k : 1 + uint32_t(rng() % k);  // the whole stretch, or part of it
        std::vector<bool> tx;  // TX after each clock, as tx_levels() tells it
        fast.tx_levels(n, [&](bool level, uint32_t m) { tx.insert(tx.end(), m, level); });
        fast.advance_line(p, n, line);
        for (uint32_t i = 0; i < n; ++i) {
          p.rx = line(0);
          ahead.pop_front();
          ref.step(p);
          ASSERT_EQ(tx[i], ref.tx()) << "TX after clock " << i + 1 << " of " << n << " at clock " << clocks;
        }
        clocks += n;
        in_bytes += n;
        ++advances;
        ASSERT_EQ(state_diff(ref, fast), "")
            << "after " << n << " clocks of a byte at clock " << clocks << ", seed " << seed;
      } else {
        pins.clock(p);
        p.rx = line(0);
        ahead.pop_front();
        ref.step(p);
        fast.step(p);
        ++clocks;
        ASSERT_TRUE(same_pins(ref, fast)) << "clock " << clocks << ", seed " << seed;
      }
    }
    ASSERT_EQ(state_diff(ref, fast), "");
    std::printf("line advance (seed %llu): %llu clocks, %llu of them inside bytes in %llu advances\n",
                (unsigned long long)seed, (unsigned long long)clocks, (unsigned long long)in_bytes,
                (unsigned long long)advances);
    EXPECT_GT(in_bytes, clocks / 10) << "seed " << seed;
    EXPECT_GT(advances, 1000u) << "seed " << seed;
  }
}

// run(p, n) is n step(p)s, whatever the state: the pins held as long as the
// line keeps its level (at most a random stretch), as a plant's step holds them.
TEST(BoardTwin, RunEqualsSteps) {
  const uint64_t seed = 501;
  Rig rig(seed, kCommands);
  auto& [rng, host, pins, ref, fast, p] = rig;
  uint64_t clocks = 0, skipped = 0;
  std::vector<bool> line;        // TX after each clock of the stretch, as run() tells it
  std::vector<uint32_t> run_of;  // the length of the run each clock came in
  uint64_t tx_edges = 0, tx_edges_skipped = 0;
  while (clocks < 1'500'000) {
    const uint32_t n = host.line(1 + uint32_t(rng() % (rng() % 3 ? 12 : 5000)), p.rx);
    pins.clock(p);
    line.clear();
    run_of.clear();
    skipped += fast.run(p, n, [&](bool level, uint32_t m) {
      line.insert(line.end(), m, level);
      run_of.insert(run_of.end(), m, m);
    });
    ASSERT_EQ(line.size(), n) << "clock " << clocks;
    // TX after every clock, stepped or skipped, is the clock-by-clock one.
    for (uint32_t i = 1; i <= n; ++i) {
      const bool tx = ref.tx();
      ref.step(p);
      ASSERT_EQ(line[i - 1], ref.tx()) << "TX after clock " << clocks + i;
      if (ref.tx() == tx) continue;
      ++tx_edges;
      tx_edges_skipped += run_of[i - 1] > 1;  // a stepped clock is a run of one
    }
    clocks += n;
    ASSERT_TRUE(same_pins(ref, fast)) << "clock " << clocks;
    // The whole state after every stretch: a walk or a segment run inside
    // one can leave a difference that the pins show only much later. (The
    // draw keeps the line's traffic as it was.)
    rng();
    ASSERT_EQ(state_diff(ref, fast), "") << "clock " << clocks;
  }
  ASSERT_EQ(state_diff(ref, fast), "");
  std::printf(
      "run (seed %llu): %llu clocks, %llu skipped, %llu TX edges, %llu of them in skipped stretches\n",
      (unsigned long long)seed, (unsigned long long)clocks, (unsigned long long)skipped,
      (unsigned long long)tx_edges, (unsigned long long)tx_edges_skipped);
  EXPECT_GT(skipped, clocks / 20);
  EXPECT_GT(tx_edges, 1000u);
  EXPECT_GT(tx_edges_skipped, tx_edges / 20);
}

// A frame cut short is dropped when the byte timeout expires, also when
// the clocks up to it are advanced over: truncated frames, then the line
// idle for longer than the timeout, with a sample period long enough for
// the wait to be skipped in long stretches.
TEST(BoardTwin, AdvanceThroughByteTimeout) {
  std::mt19937_64 rng(701);
  RxLine line;
  uint8_t seq = 1;
  line.run(true, 100);  // out of reset first
  line.bytes(hp::encode(hp::write(seq++, pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), 7000)));
  line.run(true, 3000);
  for (int i = 0; i < 60; ++i) {
    hp::Bytes b = hp::encode(hp::write(seq++, br::WDOG, 5000));
    b.resize(1 + rng() % (b.size() - 1));
    line.bytes(b);
    line.run(true, kByteTimeout + uint32_t(rng() % 5000));
  }
  Twin ref, fast;
  IcebreakerPins p;
  uint64_t clocks = 0, skipped = 0;
  while (!line.idle()) {
    const uint32_t n = line.take(1 + uint32_t(rng() % 20'000), p.rx);
    skipped += fast.run(p, n);
    for (uint32_t i = 0; i < n; ++i) ref.step(p);
    clocks += n;
    ASSERT_EQ(state_diff(ref, fast), "") << "clock " << clocks;
  }
  const uint32_t framing = fast.u_board.u_regs.shadow[Twin::Board::Regs::sidx(br::LINK_CRC)] >> 16;
  std::printf("byte timeout: %llu clocks, %llu skipped, %u frames dropped\n", (unsigned long long)clocks,
              (unsigned long long)skipped, framing);
  EXPECT_GE(framing, 50u);  // a cut after LEN > MAX_LEN or in SYNC alone may count otherwise
  EXPECT_GT(skipped, clocks * 3 / 4);
}

// ---- speed (printed, not asserted) -----------------------------------------------------

// The configuration the virtual board runs with: three axes' PID at Ts = 1200
// clocks (100 us), the watchdog at its longest, armed; telemetry of all axes
// every tlm_decim-th sample (0: off).
std::vector<hp::Frame> workload(uint32_t tlm_decim) {
  std::vector<hp::Frame> f;
  uint8_t seq = 1;
  f.push_back(hp::ping(seq++));
  for (uint8_t a = 0; a < 3; ++a) {
    f.push_back(hp::write(seq++, pid_reg::addr(a, pid_reg::KP), (1u << 20) | (16u << 24)));
    f.push_back(hp::write(seq++, pid_reg::addr(a, pid_reg::KI), (1u << 20) | (30u << 24)));
    f.push_back(hp::write(seq++, pid_reg::addr(a, pid_reg::CTRL), 1));
  }
  f.push_back(hp::write(seq++, pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), 1200));
  f.push_back(hp::write(seq++, br::WDOG, 0xFFFFFF));
  f.push_back(hp::write(seq++, br::TLM, tlm_decim | 7u << bb::T_AXES_LSB));
  f.push_back(hp::write(seq++, br::CTRL, 1u << bb::C_ARM));
  return f;
}

// Sends the frames on the line and runs until the last reply is out.
template <typename Clock>
void configure(const std::vector<hp::Frame>& frames, IcebreakerPins& p, Clock&& clock) {
  RxLine line;
  for (const auto& f : frames) {
    line.bytes(hp::encode(f));
    line.run(true, 2000);
  }
  while (!line.idle()) {
    p.rx = line.next();
    clock();
  }
  p.rx = true;
  for (int i = 0; i < 20'000; ++i) clock();
}

// The best of three runs of n clocks: on a shared machine the others' load
// only ever slows a run down.
template <typename F>
double per_second(uint64_t n, F&& f) {
  double best = 0;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f(n);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::max(best, double(n) / s);
  }
  return best;
}

TEST(BoardTwinSpeed, PrintsClocksPerSecond) {
  std::printf("board clocks per second (x real time at 12 MHz); the line idle, encoders still:\n");
  for (uint32_t decim : {0u, 10u}) {
    // The Verilated board.
    auto ctx = random_context(1);
    auto top = std::make_unique<Vtop>(ctx.get());
    IcebreakerPins p;
    const auto vclock = [&] {
      apply_pins(*top, p);
      top->CLK = 1;
      top->eval();
      top->CLK = 0;
      top->eval();
    };
    configure(workload(decim), p, vclock);
    const double v = per_second(200'000, [&](uint64_t n) {
      for (uint64_t i = 0; i < n; ++i) vclock();
    });
    const bool armed = top->rootp->motioncore_icebreaker__DOT__u_board__DOT__armed;
    top->final();

    // The twin, clock by clock and with idle clocks skipped (pins held for
    // 12 clocks, 1 us, as a plant step would hold them).
    Twin t;
    configure(workload(decim), p, [&] { t.step(p); });
    EXPECT_EQ(t.u_board.u_safety.armed_o, armed);
    Twin t2 = t;
    const double s = per_second(1'000'000, [&](uint64_t n) {
      for (uint64_t i = 0; i < n; ++i) t.step(p);
    });
    uint64_t skipped = 0;
    const double r = per_second(12'000'000, [&](uint64_t n) {
      for (uint64_t i = 0; i < n; i += 12) skipped += t2.run(p, 12);
    });
    std::printf(
        "  telemetry %-9s Verilated %6.2f M (%5.2fx)  twin step() %6.2f M (%5.2fx)  twin run() %7.2f M "
        "(%6.2fx, %.1f %% skipped)  armed %d\n",
        decim ? "every 10:" : "off:", v / 1e6, v / double(kClkHz), s / 1e6, s / double(kClkHz), r / 1e6,
        r / double(kClkHz), 100.0 * double(skipped) / 36e6, int(armed));
  }
}

}  // namespace
}  // namespace mc::test
