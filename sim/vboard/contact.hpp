// A switch contact on one of the virtual board's input pins (a home switch,
// the probe): the pin shows whether the contact is closed, and after each
// change of that (a crossing of the switch point) the contacts chatter for
// the bounce time before they settle.
//
//   Contact c(bounce_steps, seed);
//   c.settle(closed);     // power-up: the contact as it is, no bounce
//   each plant step: c.step(closed); pins.x = c.pin();
//
// The pin follows a change at once (the first touch is the true one, so a
// latch on its edge is where the switch is), then toggles at pseudo-random
// intervals of 1 to max(1, bounce_steps / 10) plant steps, and settles at
// the true state bounce_steps after the change. The intervals come from a
// generator seeded per contact: the same seed gives the same bounce on
// every engine.
#pragma once

#include <cstdint>

namespace mc::sim {

class Contact {
 public:
  Contact() = default;
  Contact(uint32_t bounce_steps, uint64_t seed)
      : bounce_(bounce_steps), longest_gap_(bounce_steps / 10 > 1 ? bounce_steps / 10 : 1), rng_(seed) {}

  void settle(bool closed) {
    truth_ = pin_ = closed;
    left_ = 0;
  }
  // One plant step on, with the contact truly closed or not.
  void step(bool closed) {
    if (closed != truth_) {
      truth_ = closed;
      set(closed);
      left_ = bounce_;
      gap_ = next_gap();
      return;
    }
    if (left_ == 0) return;
    if (--left_ == 0) {
      set(truth_);
    } else if (--gap_ == 0) {
      set(!pin_);
      gap_ = next_gap();
    }
  }

  bool pin() const { return pin_; }
  bool closed() const { return truth_; }
  bool bouncing() const { return left_ > 0; }
  // Changes of the pin so far, bounces included.
  uint64_t edges() const { return edges_; }

 private:
  void set(bool v) {
    edges_ += v != pin_;
    pin_ = v;
  }
  // splitmix64: a small, well-mixed generator; the low bits are as good as the high.
  uint32_t next_gap() {
    uint64_t z = (rng_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return 1 + uint32_t(z % longest_gap_);
  }

  uint32_t bounce_ = 0, longest_gap_ = 1;
  uint64_t rng_ = 0;
  bool truth_ = false, pin_ = false;
  uint32_t left_ = 0, gap_ = 0;
  uint64_t edges_ = 0;
};

}  // namespace mc::sim
