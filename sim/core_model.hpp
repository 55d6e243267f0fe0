// The FPGA core as the co-simulation sees it: one clock at a time, with the
// inputs and outputs of rtl/motion_core.v for the two axes of the XY table.
// Two interchangeable models: the Verilated RTL (RtlCore, sim/rtl_core.hpp)
// and the hls/ twin (TwinCore), which may also fast-forward quiet clocks.
// tests/test_motion_core_rtl.cpp holds the two to each other bit for bit, and
// the system test holds the two co-simulation paths to each other.
#pragma once

#include <cstdint>
#include <string>

#include "motion_core.hpp"

namespace mc::sim {

constexpr int kCoreAxes = 2;  // the XY table
using CoreTwin = mc::MotionCore<kCoreAxes>;
using CoreIn = CoreTwin::In;
using CoreOut = CoreTwin::Out;

class CoreModel {
 public:
  virtual ~CoreModel() = default;
  // This clock's outputs (before its edge) for these inputs.
  virtual CoreOut outputs(const CoreIn& in) = 0;
  // The same, then the edge.
  virtual CoreOut cycle(const CoreIn& in) = 0;
  // n clocks with `in` held, at once, when that changes nothing but counters;
  // false (and nothing done) otherwise. The RTL never skips.
  virtual bool try_skip(const CoreIn& in, uint32_t n) = 0;
  // The PWM counter's value in the current clock (drive models need its phase).
  virtual uint32_t pwm_count() const = 0;
  virtual const char* name() const = 0;
};

class TwinCore final : public CoreModel {
 public:
  CoreOut outputs(const CoreIn& in) override { return twin_.outputs(in.pid_we); }
  CoreOut cycle(const CoreIn& in) override {
    const CoreOut o = twin_.outputs(in.pid_we);
    twin_.clock(in);
    return o;
  }
  bool try_skip(const CoreIn& in, uint32_t n) override {
    if (!twin_.quiet(in, n)) return false;
    twin_.skip(in, n);
    return true;
  }
  uint32_t pwm_count() const override { return twin_.pwm_count(); }
  const char* name() const override { return "twin"; }

 private:
  CoreTwin twin_;
};

}  // namespace mc::sim
