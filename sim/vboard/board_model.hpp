// The board the virtual board clocks, behind one interface: the board twin
// (hls/motioncore_icebreaker.hpp), which skips the clocks in which only
// counters move, or the Verilated board top, clock by clock, for proof.
// Both see the same pins and give the same TX and drive pins every clock
// (tests/test_board_twin.cpp; tests/test_vboard.cpp holds the two virtual
// boards to each other).
//
//   auto b = make_board_model(BoardEngine::Twin, 0);
//   n = b->run(pins, limit, drive, line);  // 1..limit clocks with the pins held,
//                                          // TX after each into the receiver `line`
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "hls/motioncore_icebreaker.hpp"
#include "sim/vboard/uart_model.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::sim {

class BoardModel {
 public:
  using PinChange = mc::PinChange;
  virtual ~BoardModel() = default;
  // At least one and at most `limit` clocks with the pins p held: one
  // stepped clock, or a stretch in which nothing but counters and a frame
  // going out on TX change (DRV_EN holds; a drive may take the PID's new
  // output, its PWM and DIR following). drive[a] gains, per clock,
  // +1 (-1 with DIR) after each edge that leaves axis a's bridge on (DRV_EN
  // and PWM high); `line` takes TX after each clock. Returns the clocks done.
  virtual uint32_t run(const IcebreakerPins& p, uint32_t limit, int32_t* drive, UartReceiver& line) = 0;
  // The output pins after the last edge (TX: into run()'s `line`).
  virtual bool drv_en() const = 0;  // DRV_EN: every driver's enable
  // An axis's PWM (STEP on a stepper axis) and DIR pins.
  virtual bool pwm(int axis) const = 0;
  virtual bool dir(int axis) const = 0;
  // The spindle and coolant pins: SP_PWM, SP_EN, SP_DIR (or mist) and FLOOD.
  virtual bool sp_pwm() const = 0;
  virtual bool sp_en() const = 0;
  virtual bool sp_dir() const = 0;
  virtual bool flood() const = 0;
  // The clocks after whose edge SP_PWM was high, since power-up: the twin
  // counts them through the stretches it skips (its pin shows only the
  // last clock of one), so that the spindle's duty is exact on both engines.
  uint64_t sp_high_clocks() const { return sp_high_; }
  // The twin's fast-forward over many plant steps (the RTL: none): how many
  // of the next clocks (up to limit) with the pins held change nothing but
  // counters; the drive of axis a over the clocks [from, from + n) of such a
  // stretch (as run() counts it); advance(p, n, line) does n of them at
  // once, TX after each into `line`.
  virtual uint32_t idle_clocks(const IcebreakerPins& /*p*/, uint32_t /*limit*/) { return 0; }
  virtual int32_t idle_drive(int /*axis*/, uint32_t /*from*/, uint32_t /*n*/) const { return 0; }
  // Of up to max runs of k clocks from clock `from` of such a stretch, how
  // many in a row keep axis a's drive at one level throughout (the bridge
  // on, or off, every clock; 0: not the first).
  virtual uint32_t idle_drive_runs(int /*axis*/, uint32_t /*from*/, uint32_t /*k*/, uint32_t /*max*/) const {
    return 0;
  }
  // Encoder edges may come inside: the first `count` changes of ch (clocks
  // from the stretch's first, each at 1 or later and before n), all of them
  // allowed by idle_foldable(); p: the pins before them.
  virtual void advance(const IcebreakerPins& /*p*/, uint32_t /*n*/, UartReceiver& /*line*/,
                       const PinChange* /*ch*/, size_t /*count*/) {}
  // Of these changes of the encoder pins inside such a stretch, how many
  // in a row it may take (each an edge a decoder settles cleanly: only its
  // count moves, which nothing reads before the stretch ends).
  virtual size_t idle_foldable(const PinChange* /*ch*/, size_t /*count*/) const { return 0; }
  // TX after each of the next n clocks of such a stretch, before advance()
  // does them: f(level, clocks), as runs adding up to n.
  using Levels = std::function<void(bool, uint32_t)>;
  virtual void idle_tx(uint32_t /*n*/, const Levels& /*f*/) const {}
  // The same inside a byte on RX, with the host's line ahead of time
  // (rx(t): the RX pin in the t-th clock from now, the other pins held):
  // the stretch goes on through the byte's bits (0 while RX is idle:
  // idle_clocks() then).
  using RxLine = std::function<bool(uint64_t)>;
  virtual uint32_t line_clocks(const IcebreakerPins& /*p*/, uint32_t /*limit*/, const RxLine& /*rx*/) {
    return 0;
  }
  virtual void advance_line(const IcebreakerPins& /*p*/, uint32_t /*n*/, const RxLine& /*rx*/,
                            UartReceiver& /*line*/, const PinChange* /*ch*/, size_t /*count*/) {}
  // Clocks stepped one by one so far (the rest were skipped).
  uint64_t stepped() const { return stepped_; }
  // Appends to *words every word the command executor writes into the
  // segment queue (nullptr: off). A write is a stepped clock, never a
  // skipped one, so the tap sees each word once, in order.
  void tap_segments(std::vector<uint32_t>* words) { seg_tap_ = words; }

 protected:
  uint64_t stepped_ = 0, sp_high_ = 0;
  std::vector<uint32_t>* seg_tap_ = nullptr;
};

// seed != 0: the RTL's random power-up state, seeded (the twin powers up
// at zero: its reset makes the difference unobservable at the pins).
std::unique_ptr<BoardModel> make_board_model(BoardEngine e, uint32_t seed);

}  // namespace mc::sim
