// motioncore_icebreaker twin: the whole iCEBreaker board at its pins, clock
// by clock. Mirrors rtl/motioncore_icebreaker.v: the power-on reset, the
// two-flop synchronizers of every input but the encoders, the active-low
// LEDs, the drivers' shared enable, and under them the board core
// (hls/mc_board.hpp). For the same pin levels every clock it gives the
// RTL's TX, LED, drive, spindle and coolant pins bit for bit,
// from the same clock on (the RTL powers up at random; its reset makes the
// difference unobservable).
//
// How to drive it:
//   MotioncoreIcebreaker<> b;       // power-up: reset runs for 15 clocks
//   IcebreakerPins p;               // RX idle high, button up, all else low
//   each clock: set p; b.step(p); read b.tx(), b.pwm(a), ... (the pins after the edge)
// A host link at BAUD bit/s moves p.rx; encoders, limits (home switches),
// the probe, e-stop and the button move their pins. For long stretches with the pins held,
// run(p, n) does n clocks exactly as n step(p) would, but skips at once
// the clocks in which only counters move (idle_clocks/advance): the UART
// idle, no frame being worked on, no PID sample due, no timer expiring.
// PWM and LED pins keep following their counters inside such a stretch,
// and a frame on TX goes out (tx_levels tells the line there).
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
#pragma once

#include <cstdint>

#include "mc_board.hpp"

namespace mc {

// The board's input pins (rtl/motioncore_icebreaker.v's names; per axis
// [0] X, [1] Y, [2] Z).
struct IcebreakerPins {
  bool rx = true;                     // RX: FTDI UART, idles high
  bool btn_n = true;                  // BTN_N: the user button, low when pressed (a local stop)
  bool estop = false;                 // ESTOP
  bool probe = false;                 // PROBE
  bool enc_a[3] = {}, enc_b[3] = {};  // X_ENC_A, ... (no index pins on this board)
  bool lim[3] = {};                   // X_LIM, ...: limit and home switches
  bool hw_a = false, hw_b = false;    // HW_A, HW_B: the handwheel
};

template <int NAXES = 3, int CLK_HZ = 12'000'000, int BAUD = 1'000'000, bool HANDWHEEL = true,
          int STEPPERS = 0, bool SERVO = true>
class MotioncoreIcebreaker {
  static_assert(NAXES >= 1 && NAXES <= 3, "motioncore_icebreaker: NAXES must be 1..3");

 public:
  using Board = McBoard<NAXES, 9, 9, 4, CLK_HZ, BAUD, HANDWHEEL, STEPPERS, SERVO>;
  static constexpr int NS = 4 + NAXES;  // synchronized inputs: {RX, probe, button, e-stop, limits}

  uint8_t por = 0;         // power-on reset counter, 4 bits
  uint8_t s1 = 0, s2 = 0;  // the synchronizers, NS bits
  Board u_board;

  bool rst() const { return por != 15; }

  // The output pins after the last edge.
  bool tx() const { return u_board.tx_o(); }
  bool pwm(int a) const { return a < NAXES && u_board.pwm_o(a); }  // STEP on a stepper axis
  bool dir(int a) const { return a < NAXES && u_board.dir_o(a); }
  bool drv_en() const {  // DRV_EN: every driver's enable
    for (int a = 0; a < NAXES; ++a)
      if (u_board.drv_en_o(a)) return true;
    return false;
  }
  bool sp_pwm() const { return u_board.sp_pwm_o(); }
  bool sp_en() const { return u_board.sp_en_o(); }
  bool sp_dir() const { return u_board.sp_dir_o(); }  // or mist (IO_CTRL.mist_on_dir)
  bool flood() const { return u_board.flood_o(); }
  bool ledr_n() const { return !u_board.led_fault_o(); }
  bool ledg_n() const { return !u_board.led_ok_o(); }
  // Over edges from .. from + n - 1 of the stretch idle_clocks() found,
  // when advance(p, n) does them: axis a's PWM (STEP) pin high after the
  // edge, -1 with DIR set, else +1 (EN holds; a servo's drive may take the
  // PID's new output inside, from edge drive_change(a) on).
  int32_t drive_in(int a, uint32_t from, uint32_t n) const {
    return a < NAXES ? u_board.drive_in(a, from, n) : 0;
  }
  // Of up to max runs of k edges from edge `from` of that stretch, how many
  // in a row leave axis a's PWM (STEP) pin at one level throughout.
  uint32_t drive_runs(int a, uint32_t from, uint32_t k, uint32_t max) const {
    return a < NAXES ? u_board.drive_runs(a, from, k, max) : max;
  }
  static constexpr uint32_t kNoChange = Board::Core::kNoChange;
  uint32_t drive_change(int a) const { return a < NAXES ? u_board.drive_change(a) : kNoChange; }
  uint64_t sp_high_in(uint32_t n) const { return u_board.u_io.sp_high_in(n); }

  // One rising clock edge with these pin levels.
  void step(const IcebreakerPins& p) {
    u_board.clock(board_in(p));
    s2 = s1;
    s1 = sync_in(p);
    if (rst()) por = uint8_t(por + 1);
    idle_ = 0;
  }

  // How many of the next clocks (up to limit) with these pins held change
  // nothing but counters and timers; advance(p, n) does n <= that many at
  // once, leaving exactly the state n step(p) would leave.
  uint32_t idle_clocks(const IcebreakerPins& p, uint32_t limit) {
    const uint32_t w = pins_word(p);
    if (idle_ == 0 || w != idle_pins_) {  // else: what is left of the stretch found before
      idle_pins_ = w;
      idle_ = rst() || s1 != sync_in(p) || s2 != s1 ? 0 : u_board.quiet(board_in(p), 0xFFFFFFFFu);
    }
    return idle_ < limit ? idle_ : limit;
  }
  void advance(const IcebreakerPins& p, uint32_t n) { advance(p, n, nullptr, 0); }
  // The same with encoder edges inside (ch: changes of the encoder pins,
  // clocks from the stretch's first, each at 1 or later; the first `count`
  // of them, all before clock n, those that foldable() allows). p: the pins
  // before them.
  using PinChange = mc::PinChange;
  size_t foldable(const PinChange* ch, size_t count) const { return u_board.foldable(ch, count); }
  void advance(const IcebreakerPins& p, uint32_t n, const PinChange* ch, size_t count) {
    u_board.skip(n, ch, count);
    // Edges leave other pins: the stretch is found again.
    idle_ = count == 0 && pins_word(p) == idle_pins_ && idle_ >= n ? idle_ - n : 0;
  }
  // Inside a byte on RX, with the line's future known: line(t) is the RX
  // pin in the t-th clock from now (line(0) == p.rx), every other pin held.
  // The clocks (up to limit) in which nothing but counters, the receiver's
  // bits and the synchronizer's RX stage move, up to the byte's stop bit;
  // advance_line(p, n, line) does them (not RTL). 0 with the receiver
  // idle: the pins held, idle_clocks() finds the stretch.
  template <typename Line>
  uint32_t line_clocks(const IcebreakerPins& p, uint32_t limit, Line&& line) {
    const uint8_t in = sync_in(p);
    idle_ = 0;  // quiet_line() leaves the board's fast-forward state for its own stretch
    if (rst() || !u_board.u_urx.busy || ((s1 ^ in) | (s2 ^ in)) & ~kRx) return 0;
    return u_board.quiet_line(board_in(p), limit, synced(line));
  }
  template <typename Line>
  void advance_line(const IcebreakerPins& p, uint32_t n, Line&& line, const PinChange* ch = nullptr,
                    size_t count = 0) {
    if (n == 0) return;
    u_board.skip_line(n, synced(line), ch, count);
    const auto at = [&](uint32_t t) { return uint8_t((sync_in(p) & ~kRx) | (line(t) ? kRx : 0)); };
    s2 = n >= 2 ? at(n - 2) : s1;
    s1 = at(n - 1);
    idle_ = 0;
  }

  // TX after each of the next n clocks that advance(p, n) would do, as runs
  // (f(level, clocks), in order): a frame going out keeps the stretch going
  // (not RTL).
  template <typename F>
  void tx_levels(uint32_t n, F&& f) const {
    u_board.tx_levels(n, f);
  }

  // n clocks with these pins held: step(p) where something happens,
  // advance() over the rest. Returns how many clocks were skipped.
  // line(level, clocks) tells TX after every clock of the call, in order, as
  // runs (a stepped clock is a run of one), so that a host can decode it.
  template <typename Line>
  uint64_t run(const IcebreakerPins& p, uint64_t n, Line&& line) {
    uint64_t skipped = 0, done = 0;
    while (done < n) {
      const uint64_t left = n - done;
      const uint32_t k = idle_clocks(p, left > 0xFFFFFFFFu ? 0xFFFFFFFFu : uint32_t(left));
      if (k > 0) {
        tx_levels(k, line);
        advance(p, k);
        skipped += k;
        done += k;
      } else {
        step(p);
        line(tx(), uint32_t(1));
        ++done;
      }
    }
    return skipped;
  }
  uint64_t run(const IcebreakerPins& p, uint64_t n) {
    return run(p, n, [](bool, uint32_t) {});
  }

 private:
  uint8_t sync_in(const IcebreakerPins& p) const {
    uint32_t v = uint32_t(p.rx) << (NS - 1) | uint32_t(p.probe) << (NAXES + 2) |
                 uint32_t(!p.btn_n) << (NAXES + 1) | uint32_t(p.estop) << NAXES;
    for (int a = 0; a < NAXES; ++a) v |= uint32_t(p.lim[a]) << a;
    return uint8_t(v);
  }
  McBoardIn board_in(const IcebreakerPins& p) const {
    McBoardIn b;
    b.rst = rst();
    b.rx = s2 >> (NS - 1) & 1;
    b.probe = s2 >> (NAXES + 2) & 1;
    b.stop = s2 >> (NAXES + 1) & 1;
    b.estop = s2 >> NAXES & 1;
    b.lim = uint8_t(s2 & ((1u << NAXES) - 1));
    for (int a = 0; a < NAXES; ++a) {
      b.enc_a = uint8_t(b.enc_a | uint32_t(p.enc_a[a]) << a);
      b.enc_b = uint8_t(b.enc_b | uint32_t(p.enc_b[a]) << a);
    }
    b.hw_a = p.hw_a;
    b.hw_b = p.hw_b;
    return b;
  }
  static constexpr uint8_t kRx = uint8_t(1u << (NS - 1));  // RX's bit in the synchronizers
  // The receiver's input in the t-th clock from now: the synchronizer's
  // stages, then the pin two clocks earlier.
  template <typename Line>
  auto synced(Line& line) const {
    return [this, &line](uint32_t t) {
      return t == 0 ? bool(s2 & kRx) : t == 1 ? bool(s1 & kRx) : bool(line(t - 2));
    };
  }
  static uint32_t pins_word(const IcebreakerPins& p) {
    uint32_t w = uint32_t(p.rx) | uint32_t(p.btn_n) << 1 | uint32_t(p.estop) << 2 | uint32_t(p.hw_a) << 3 |
                 uint32_t(p.hw_b) << 4 | uint32_t(p.probe) << 5;
    for (int a = 0; a < 3; ++a)
      w |= (uint32_t(p.enc_a[a]) | uint32_t(p.enc_b[a]) << 1 | uint32_t(p.lim[a]) << 2) << (6 + 3 * a);
    return w;
  }

  // The idle stretch found last (a stretch stays idle to its end while the
  // pins hold): clocks left, and the pins it was found with. A test that
  // writes registers by hand steps a clock before it advances again.
  uint32_t idle_ = 0, idle_pins_ = 0;
};

}  // namespace mc
