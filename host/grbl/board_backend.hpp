// The Grbl front end on the board (real or virtual): each line's canonical
// calls become planned moves (host/motion planner) that a JobStreamer, the
// same one `motionctl run` uses, feeds to the board's segment queue as they
// arrive, replanning the part not yet sent with look-ahead over everything
// queued. Holds, resumes, overrides and jog cancels act on that plan; a soft
// reset stops the interpolator at once.
//
// The server loop calls tick() every round: one round of the link (what the
// board has done, more segments, the axes' positions), never waiting for the
// motion, so `?` is answered while a job runs. Board faults become alarms
// naming the fault; the drives are armed again with the next line once the
// fault's cause is gone. Spindle and coolant drive the board's IO_CTRL in
// order with the motion. Positions are machine coordinates from the board's
// origin (ORIGIN). `$H` runs the homing cycle (host/machine/cycles.hpp)
// from tick(), with the machine file's [home] tables as $23..$27 adjust
// them, and moves the origin with it; G38.x runs the probing cycle once the
// moves before it are done, and reports where the probe latched.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <utility>

#include "host/grbl/backend.hpp"
#include "host/grbl/settings.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/cycles.hpp"
#include "host/machine/height_map.hpp"
#include "host/machine/machine_config.hpp"
#include "host/machine/mpg.hpp"
#include "host/machine/spindle.hpp"
#include "host/motion/job_stream.hpp"

namespace mc::grbl {

// The WDOG value of a watchdog period (clock cycles); InputError beyond what
// the register holds.
uint32_t watchdog_cycles(double period_s, double clock_hz);

class BoardBackend : public Backend {
 public:
  // `l`: a connected link. Readies the board as `motionctl run` does
  // (mc::machine::ready_board: gains where missing, armed, PIDs and
  // following-error limits on) and starts where the axes are. watchdog_s:
  // the board's watchdog period while serving (0: leave the board's, 100 ms
  // after its reset); InputError beyond what the register holds.
  BoardBackend(mc::host::BoardLink& l, const mc::machine::MachineConfig& m, int planner_blocks = 16,
               const mc::host::Note& note = {}, double watchdog_s = 0);

  // One round of the link; throws LinkError when the board stops answering.
  void tick();

  void configure(const Settings& settings) override;
  bool ready() const override;
  void submit(Submission line) override;
  bool drained() const override;
  void feed_hold() override;
  void cycle_start() override;
  void jog_cancel() override;
  void soft_reset() override;
  void set_overrides(const Overrides& o) override;
  Status status() const override;
  int planner_blocks() const override { return blocks_; }
  std::optional<Event> poll_event() override;
  int home(unsigned axis_mask) override;
  std::string height_map() const override;
  bool levelling() const override { return map_ && level_on_; }
  int set_levelling(bool on) override;
  // The bed's height map (motionctl serve --level FILE): every line that is
  // not a jog is levelled with it (host/machine/height_map.hpp) while
  // levelling is on, which this turns on. `name`: what $LEV calls it.
  void set_height_map(const mc::machine::HeightMap& map, const std::string& name);
  std::string mpg() const override;
  int set_mpg(const std::string& selection) override;

  // The planner's limits now ($110.. and $120.. within the machine's).
  const mc::host::PlannerConfig& planner() const { return cfg_; }

 private:
  void arm();
  void read_positions();
  void fault(uint32_t bits);
  void action(const mc::host::Move& m);
  // The cycles, one round each from tick().
  void poll_homing();
  void poll_probe();
  // After a cycle moved the command outside the streamer: plan from where
  // it stands, in the board's (possibly new) machine frame.
  void resync();
  void cycle_failed(int alarm, const std::string& what);
  // The handwheel jogs while nothing else runs: on the board while idle,
  // off (what is pending dropped) before anything else moves, the streamer
  // then starting where the wheel left the command.
  void update_wheel();
  void release_wheel();

  mc::host::BoardLink& l_;
  mc::machine::MachineConfig machine_;
  mc::host::PlannerConfig base_, cfg_;
  int blocks_;
  mc::host::Note note_;
  std::unique_ptr<mc::host::JobStreamer> s_;
  bool armed_ = false;
  // Lines queued and not yet finished: (key, N word). A move's `line` is its
  // submission's key, counting from 1.
  std::deque<std::pair<int, int>> lines_;
  int next_key_ = 1;
  gcode::Vec3 pos_{};  // machine mm, from the encoders
  Pins pins_;
  // Motion has stopped on the board but an axis is not yet within
  // kInPosition counts of its command: a stop (Idle, Hold:0) is reported
  // once the servo has settled there, or kSettleTimeout after it stopped.
  bool settling_ = false;
  std::optional<std::chrono::steady_clock::time_point> stopped_at_;
  Overrides ovr_;
  mc::machine::SpindleState spindle_;  // as the program set it; IO_CTRL follows
  // The spindle and coolant off, on the board too (after a reset or a
  // fault: the board drops the pins while disarmed, and must not raise them
  // again when the next line rearms it).
  void spindle_off();
  std::deque<Event> events_;
  std::optional<Settings> settings_;  // the sender's, once configure() had them
  std::optional<mc::machine::HomingCycle> homing_;
  // A G38.x line: waits for the moves before it, then runs as `cycle`.
  struct Probing {
    gcode::StraightProbe op;
    std::optional<mc::machine::ProbeCycle> cycle;
  };
  std::optional<Probing> probe_;
  std::optional<mc::machine::HeightMap> map_;
  std::string map_name_;
  bool level_on_ = false;
  bool has_wheel_ = false;                  // the board's INFO
  mc::machine::MpgSetting mpg_, wheel_on_;  // as the sender selected; as the board has it
};

}  // namespace mc::grbl
