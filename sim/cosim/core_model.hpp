// The FPGA core as the co-simulation sees it: one clock at a time, with the
// inputs and outputs of rtl/motion_core.v for the two axes of the XY table.
// Two interchangeable models: the Verilated RTL (RtlCore, sim/rtl_core.hpp)
// and the hls/ twin (TwinCore), which may also fast-forward quiet clocks
// (MotionCore::quiet_busy: the interpolator may iterate meanwhile).
// tests/test_motion_core_rtl.cpp holds the two to each other bit for bit, and
// the system test holds the two co-simulation paths to each other.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "hls/motion_core.hpp"

namespace mc::sim {

constexpr int kCoreAxes = 2;  // the XY table
using CoreTwin = mc::MotionCore<kCoreAxes>;
using CoreIn = CoreTwin::In;
using CoreOut = CoreTwin::Out;

// What a fast-forward skipped: the outputs of its first clock and the PWM
// counter then, from which the drive over the skipped clocks follows, and
// each axis's drive value over them (the sweep may update it meanwhile).
using DriveSteps = CoreTwin::DriveSteps;
struct Skipped {
  CoreOut first;
  uint32_t pwm0 = 0;
  DriveSteps drive[kCoreAxes] = {};
};
// A skip's change of the position command: after its clock-th edge (from
// 1) the command is cmd.
struct CmdChange {
  uint32_t clock = 0;
  int32_t cmd[kCoreAxes] = {};
};
// An encoder's new pins inside a skip (CoreTwin::PinChange).
using PinChange = CoreTwin::PinChange;

class CoreModel {
 public:
  virtual ~CoreModel() = default;
  // This clock's outputs (before its edge) for these inputs, then the edge.
  // The RTL fills those the co-simulation reads: pid_wready, seg_count,
  // ip_underrun, tick, done and, per axis, pwm, dir, drv_en, drv_u, drv_cmd
  // and cmd.
  virtual CoreOut cycle(const CoreIn& in) = 0;
  // How many of the next clocks (up to limit) skip() may take with `in`
  // held: clocks in which nothing changes but counters, the PWM pins and
  // the position command of a running segment (0: none; the RTL never
  // skips).
  virtual uint32_t quiet_clocks(const CoreIn& /*in*/, uint32_t /*limit*/) const { return 0; }
  // The same for a jump's skips, and where it gives 0, whether this clock
  // is not quiet only because it is the PID's or the sample port's
  // (CoreTwin::Let::sample) and leaves the interpolator's segment running,
  // so that a jump cycles it (the twin; for the checks of one). again: in
  // is what the last call was given, and only skip() and cycle() with it
  // came since (the twin then asks only what those can change).
  virtual uint32_t quiet_clocks(const CoreIn& in, uint32_t limit, bool& sample, bool /*again*/) const {
    sample = false;
    return quiet_clocks(in, limit);
  }
  // Up to n of those clocks at once: returns how many it did (it stops
  // before a segment ends) and, unless first is null, the outputs and PWM
  // counter of the first; appends each change of the position command to
  // *changes.
  virtual uint32_t skip(const CoreIn& /*in*/, uint32_t /*n*/, Skipped* /*first*/,
                        std::vector<CmdChange>& /*changes*/) {
    return 0;
  }
  // Of these pin changes (in clock order, from clock 1 of a skip from
  // here with `in` on), how many in a row the skip may take instead of
  // ending at each (the twin: CoreTwin::foldable)...
  virtual size_t foldable(const CoreIn& /*in*/, const PinChange* /*ch*/, size_t /*count*/) const { return 0; }
  // ... and skip() taking them (`count` of them foldable; first: none).
  virtual uint32_t skip_edges(const CoreIn& in, uint32_t n, std::vector<CmdChange>& changes,
                              const PinChange* /*ch*/, size_t count) {
    return count == 0 ? skip(in, n, nullptr, changes) : 0;
  }
  // Of this clock's outputs, without the edge (the twin): the words queued
  // for the interpolator, and axis a's drive command (a sample's output).
  virtual int seg_count() const { return 0; }
  virtual int16_t drv_cmd(int /*a*/) const { return 0; }
  // Axis a's drive value over the clocks that skip(in, ..) would do (the
  // twin)...
  virtual DriveSteps drive_steps(const CoreIn& /*in*/, int /*a*/) const { return {}; }
  // ... and over how many clocks from this one, skips and sample clocks
  // alike: up to the next sample's first drive update.
  virtual uint32_t known_drive_clocks() const { return 0; }
  // This clock ends the running segment (the twin).
  virtual bool segment_ends() const { return false; }
  // The clocks from this one to the PID's done (0: this one), kNoDone with
  // no sweep under way: a jump's skips go through done (the twin), the
  // sample's outputs then recorded from after the skip.
  static constexpr uint32_t kNoDone = CoreTwin::Pid::kNoDone;
  virtual uint32_t done_in() const { return kNoDone; }
  // The position command now (the twin; after a skip).
  virtual int32_t cmd(int /*a*/) const { return 0; }
};

// drive: skips may go through the sweep's drive updates (a user that
// integrates the drive value over a skip from Skipped::drive) and end with
// the edge before a PID sample's tick or done (a jump's go through both:
// quiet_clocks() with `sample` and skip_edges()); else they end before each.
class TwinCore final : public CoreModel {
 public:
  explicit TwinCore(bool drive = false)
      : let_{false, true, true, drive, drive}, jump_let_{false, true, true, drive, drive, drive, drive} {}
  CoreOut cycle(const CoreIn& in) override {
    const CoreOut o = used_outputs();
    twin_.clock(in);
    return o;
  }
  uint32_t quiet_clocks(const CoreIn& in, uint32_t limit) const override {
    const uint32_t n = std::min(limit, twin_.quiet_limit_as(let_));
    return n > 0 && twin_.quiet_as(in, n, let_) ? n : 0;
  }
  uint32_t quiet_clocks(const CoreIn& in, uint32_t limit, bool& sample, bool again) const override {
    const uint32_t n = std::min(limit, twin_.quiet_limit_as(jump_let_));
    const bool known = again && others_;
    const int k =
        known ? twin_.quiet_or_pid_again(in, n, jump_let_) : twin_.quiet_or_pid(in, n, jump_let_, &others_);
    sample = k == CoreTwin::kPidClock && jump_let_.sample && !segment_ends();
    return k == CoreTwin::kQuiet ? n : 0;
  }
  DriveSteps drive_steps(const CoreIn& in, int a) const override { return twin_.drive_steps(in, a); }
  uint32_t known_drive_clocks() const override { return twin_.known_drive_clocks(); }
  bool segment_ends() const override { return twin_.interp().ending(); }
  uint32_t skip(const CoreIn& in, uint32_t n, Skipped* first, std::vector<CmdChange>& changes) override {
    if (first) {
      first->first = used_outputs();
      first->pwm0 = twin_.pwm_count();
      for (int a = 0; a < kCoreAxes; ++a) first->drive[a] = twin_.drive_steps(in, a);
    }
    return twin_.skip_busy_as(in, n, let_, moved_to(changes));
  }
  size_t foldable(const CoreIn& in, const PinChange* ch, size_t count) const override {
    return twin_.foldable(in, ch, count);
  }
  uint32_t skip_edges(const CoreIn& in, uint32_t n, std::vector<CmdChange>& changes, const PinChange* ch,
                      size_t count) override {
    return twin_.skip_busy_as(in, n, jump_let_, moved_to(changes), ch, count);
  }
  uint32_t done_in() const override { return twin_.done_in(); }
  int seg_count() const override { return twin_.interp().count(); }
  int16_t drv_cmd(int a) const override { return twin_.drv_cmd(a); }
  int32_t cmd(int a) const override { return twin_.interp().pos(a); }

 private:
  // What a skip tells of each clock that moved the command: the command
  // after it, appended to *changes.
  struct MovedTo {
    const CoreTwin* twin;
    std::vector<CmdChange>* changes;
    void operator()(uint32_t clock) const {
      CmdChange c;
      c.clock = clock;
      for (int a = 0; a < kCoreAxes; ++a) c.cmd[a] = twin->interp().pos(a);
      changes->push_back(c);
    }
  };
  MovedTo moved_to(std::vector<CmdChange>& changes) const { return MovedTo{&twin_, &changes}; }
  // The outputs the co-simulation reads after configuring the core (as
  // the RTL engine fills them), for much less than outputs() gathers.
  CoreOut used_outputs() const {
    CoreOut o;
    o.pid_wready = twin_.pid().wready();
    o.seg_count = twin_.interp().count();
    o.ip_underrun = twin_.interp().underrun();
    o.tick = twin_.pid().tick();
    o.done = twin_.pid().done();
    for (int a = 0; a < kCoreAxes; ++a) {
      o.pwm[a] = twin_.pwm(a);
      o.dir[a] = twin_.dir(a);
      o.drv_en[a] = twin_.drv_en(a);
      o.drv_u[a] = twin_.drv_u(a);
      o.drv_cmd[a] = twin_.drv_cmd(a);
      o.cmd[a] = twin_.interp().pos(a);
    }
    return o;
  }
  CoreTwin::Let let_, jump_let_;
  CoreTwin twin_;
  // What the last quiet_clocks() found of the checks but the PID's.
  mutable bool others_ = false;
};

}  // namespace mc::sim
