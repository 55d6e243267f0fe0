// A stepper driver as the datasheets of the A4988 and DRV8825 describe its
// STEP/DIR input: a step on each rising edge of STEP, in the direction DIR
// had at that edge. It checks the timing those datasheets ask of the
// controller (minimum high and low pulse widths, DIR setup before the
// rising edge and hold after it), in clocks, and counts violations instead
// of steps it would miss.
#pragma once

#include <cstdint>

namespace mc::test {

class StepDriver {
 public:
  StepDriver(uint32_t min_high, uint32_t min_low, uint32_t min_setup)
      : min_high_(min_high), min_low_(min_low), min_setup_(min_setup) {}

  // The pins during one clock.
  void clock(bool step, bool dir) {
    const bool turned = dir != dir_;
    if (step && !step_) {
      ++pulses_;
      pos_ += dir ? 1 : -1;
      if (!first_ && low_ < min_low_) ++short_low_;
      if (turned || dir_age_ < min_setup_) ++short_setup_;
      high_ = 0;
      first_ = false;
    } else if (!step && step_) {
      if (high_ < min_high_) ++short_high_;
      low_ = 0;
    }
    if (turned) {
      if (step || step_) ++dir_in_pulse_;
      dir_age_ = 0;
    }
    // Counted after the edge: a level held this clock.
    if (step)
      ++high_;
    else
      ++low_;
    ++dir_age_;
    step_ = step;
    dir_ = dir;
  }

  int64_t position() const { return pos_; }
  int64_t pulses() const { return pulses_; }
  // Timing violations of each kind.
  int64_t short_high() const { return short_high_; }
  int64_t short_low() const { return short_low_; }
  int64_t short_setup() const { return short_setup_; }
  int64_t dir_in_pulse() const { return dir_in_pulse_; }

 private:
  uint32_t min_high_, min_low_, min_setup_;
  bool step_ = false, dir_ = true, first_ = true;
  uint64_t high_ = 0, low_ = 0, dir_age_ = 1u << 30;
  int64_t pos_ = 0, pulses_ = 0;
  int64_t short_high_ = 0, short_low_ = 0, short_setup_ = 0, dir_in_pulse_ = 0;
};

}  // namespace mc::test
