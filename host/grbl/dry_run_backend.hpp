// A machine without hardware for the Grbl front end: it runs the queued
// canonical calls kinematically (straight lines and arcs at the commanded
// feed, limited by the max rates, with the acceleration as the only
// dynamics, dwells by the clock, a probe that touches a plane), so that a
// sender can be tried against `motionctl serve --dry-run` and the protocol
// tests have a machine with a real queue and real timing.
//
// It has no look-ahead: speed ramps at the acceleration toward each block's
// feed and carries across corners unchanged, except into a feed hold, a jog
// cancel or a dwell, which decelerate (holds, cancels) or stop (dwells). Time
// is advanced by the caller (advance()), so tests are deterministic.
#pragma once

#include <deque>
#include <optional>

#include "host/grbl/backend.hpp"
#include "host/grbl/settings.hpp"

namespace mc::grbl {

class DryRunBackend : public Backend {
 public:
  explicit DryRunBackend(int planner_blocks = 16, gcode::Vec3 start = {});

  // Runs the machine for dt seconds.
  void advance(double dt_s);
  double time_s() const { return time_s_; }

  // The probe input turns on below this Z (machine mm); none: never.
  void set_probe_surface(std::optional<double> z_mm) { probe_z_ = z_mm; }
  // A board fault: the machine stops and reports `alarm`.
  void inject_fault(const AlarmEvent& alarm);
  // Every submission received, in order (tests check that nothing was lost).
  const std::vector<Submission>& received() const { return received_; }
  void keep_received(bool keep) { keep_ = keep; }
  const Overrides& overrides() const { return ovr_; }
  const Settings& settings() const { return settings_; }

  void configure(const Settings& settings) override { settings_ = settings; }
  bool ready() const override;
  void submit(Submission line) override;
  bool drained() const override;
  void feed_hold() override;
  void cycle_start() override;
  void jog_cancel() override;
  void soft_reset() override;
  void set_overrides(const Overrides& o) override { ovr_ = o; }
  Status status() const override;
  int planner_blocks() const override { return blocks_; }
  std::optional<Event> poll_event() override;
  int home(unsigned axis_mask) override;

 private:
  struct Block {
    gcode::CanonCall call;
    int line_number = 0;
    bool jog = false;
    gcode::Vec3 start{};
    double length = 0;  // mm; 0 for what does not move
  };
  bool moves(const Block& b) const { return b.length > 0; }
  double target_speed(const Block& b) const;  // mm/s
  gcode::Vec3 point(const Block& b, double s) const;
  void begin(Block& b);
  // Moves up to `dist` mm along the queue; returns what was not used.
  double travel(double dist);
  void finish_head();

  int blocks_;
  Settings settings_;
  Overrides ovr_;
  std::deque<Block> queue_;
  bool head_started_ = false;
  double done_mm_ = 0;     // along the head block
  double dwell_left_ = 0;  // s, of the head dwell
  gcode::Vec3 pos_{};
  double v_ = 0;  // mm/s
  bool hold_ = false, cancel_ = false;
  int spindle_ = 0;
  double rpm_ = 0;
  bool flood_ = false, mist_ = false;
  std::optional<double> probe_z_;
  std::deque<Event> events_;
  std::vector<Submission> received_;
  bool keep_ = false;
  double time_s_ = 0;
};

}  // namespace mc::grbl
