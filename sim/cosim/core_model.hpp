// The FPGA core as the co-simulation sees it: one clock at a time, with the
// inputs and outputs of rtl/motion_core.v for the two axes of the XY table.
// Two interchangeable models: the Verilated RTL (RtlCore, sim/rtl_core.hpp)
// and the hls/ twin (TwinCore), which may also fast-forward quiet clocks.
// tests/test_motion_core_rtl.cpp holds the two to each other bit for bit, and
// the system test holds the two co-simulation paths to each other.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>

#include "hls/motion_core.hpp"

namespace mc::sim {

constexpr int kCoreAxes = 2;  // the XY table
using CoreTwin = mc::MotionCore<kCoreAxes>;
using CoreIn = CoreTwin::In;
using CoreOut = CoreTwin::Out;

// What a fast-forward skipped: the outputs of its first clock and the PWM
// counter then, from which the drive over the skipped clocks follows.
struct Skipped {
  CoreOut first;
  uint32_t pwm0 = 0;
};

class CoreModel {
 public:
  virtual ~CoreModel() = default;
  // This clock's outputs (before its edge) for these inputs, then the edge.
  // The RTL fills those the co-simulation reads: pid_wready, seg_count,
  // ip_underrun, tick, done and, per axis, pwm, dir, drv_en, drv_u, drv_cmd
  // and cmd.
  virtual CoreOut cycle(const CoreIn& in) = 0;
  // n clocks with `in` held, at once, when that changes nothing but counters;
  // nullopt (and nothing done) otherwise. The RTL never skips.
  virtual std::optional<Skipped> try_skip(const CoreIn& in, uint32_t n) = 0;
  // How many of the next clocks (up to limit) try_skip would take with `in`
  // held (0: none; the RTL never skips).
  virtual uint32_t quiet_clocks(const CoreIn& /*in*/, uint32_t /*limit*/) const { return 0; }
  // This clock's outputs and PWM counter, without the edge (the twin).
  virtual CoreOut peek(const CoreIn& /*in*/) const { return CoreOut{}; }
  virtual uint32_t pwm_count() const { return 0; }
};

class TwinCore final : public CoreModel {
 public:
  CoreOut cycle(const CoreIn& in) override {
    const CoreOut o = twin_.outputs(in.pid_we);
    twin_.clock(in);
    return o;
  }
  std::optional<Skipped> try_skip(const CoreIn& in, uint32_t n) override {
    if (!twin_.quiet(in, n)) return std::nullopt;
    Skipped s{twin_.outputs(in.pid_we), twin_.pwm_count()};
    twin_.skip(n);
    return s;
  }
  uint32_t quiet_clocks(const CoreIn& in, uint32_t limit) const override {
    const uint32_t n = std::min(limit, twin_.quiet_limit());
    return n > 0 && twin_.quiet(in, n) ? n : 0;
  }
  CoreOut peek(const CoreIn& in) const override { return twin_.outputs(in.pid_we); }
  uint32_t pwm_count() const override { return twin_.pwm_count(); }

 private:
  CoreTwin twin_;
};

}  // namespace mc::sim
