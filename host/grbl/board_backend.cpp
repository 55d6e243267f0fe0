#include "host/grbl/board_backend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/job.hpp"

namespace mc::grbl {
namespace {

namespace br = board::reg;
namespace bb = board::bits;
using mc::host::JobStreamer;

constexpr int kSettingDisabled = 5;
constexpr int kInvalidStatement = 3;
constexpr int kNotIdle = 8;
constexpr int kAlarmHardLimit = 1;
constexpr int kAlarmSoftLimit = 2;
constexpr int kAlarmAbortCycle = 3;
using mc::host::kInPosition;
using mc::host::kSettleTimeout;

// A handwheel selection as Grbl replies show it: "X10" ($MPG), "X,10" (HW:).
std::string wheel_text(const mc::machine::MpgSetting& s, const char* between) {
  return std::string(1, "XYZ"[s.axis]) + between + std::to_string(s.step);
}

bool limit_fault(uint32_t bits) {
  return bits & (0x7u << bb::F_LIMIT_LSB);
}

// $23..$27 on the machine file's homing. Grbl's are one value for every
// axis, the file's one per axis: a setting the sender left at its default
// (which the file gave, settings.cpp) keeps each axis's own, one it changed
// applies to every axis. $23 flips an axis's search direction as in Grbl
// (bit set: towards -), which finds nothing if the switch is not there.
// $26 has nothing to act on: the board filters the switches itself.
void apply_homing_settings(mc::machine::HomingPlan& plan, const Settings& s, const Settings& def) {
  for (auto& pass : plan.passes)
    for (mc::machine::HomeAxis& x : pass) {
      if (s.homing_dir_mask != def.homing_dir_mask) x.direction = (s.homing_dir_mask >> x.axis & 1) ? -1 : 1;
      if (s.homing_feed_mm_min != def.homing_feed_mm_min) x.locate_mm_min = s.homing_feed_mm_min;
      if (s.homing_seek_mm_min != def.homing_seek_mm_min) x.seek_mm_min = s.homing_seek_mm_min;
      if (s.homing_pulloff_mm != def.homing_pulloff_mm) x.pull_off_mm = s.homing_pulloff_mm;
    }
}

}  // namespace

uint32_t watchdog_cycles(double period_s, double clock_hz) {
  const double top = double((1u << board::WDOG_W) - 1) / clock_hz;
  const double cycles = std::round(period_s * clock_hz);
  if (!(cycles >= 1) || period_s > top)
    throw mc::host::InputError("watchdog period", mc::host::format_number(period_s) + " s",
                               "0 < period <= " + mc::host::format_number(top) + " s (WDOG is " +
                                   std::to_string(board::WDOG_W) + " bits of clock cycles)");
  return uint32_t(cycles);
}

BoardBackend::BoardBackend(mc::host::BoardLink& l, const mc::machine::MachineConfig& m, int planner_blocks,
                           const mc::host::Note& note, double watchdog_s)
    : l_(l), machine_(m), blocks_(planner_blocks), note_(note) {
  if (watchdog_s > 0) l_.write(br::WDOG, watchdog_cycles(watchdog_s, m.clock_hz));
  const mc::machine::JobBoard b = mc::machine::ready_board(l_, machine_, note_);
  // MPos and every line in machine coordinates: from the board's machine
  // zero once homed, as `motionctl run` plans.
  base_ = cfg_ = mc::machine::planner_config(m, b.origin);
  s_ = std::make_unique<JobStreamer>(l_, cfg_, b.at, m.planner.queue_ahead_s);
  s_->on_action = [this](const mc::host::Move& mv) { action(mv); };
  armed_ = true;
  has_wheel_ = bb::info_handwheel(l_.read(br::INFO));
  if (has_wheel_) mc::machine::set_mpg(l_, machine_, {});  // the sender selects it ($MPG)
  read_positions();
}

void BoardBackend::configure(const Settings& settings) {
  // The board's scales are its encoders': $100..$102 stay for senders. Rates
  // and accelerations apply within the machine's limits, which its motors
  // and the following-error limit were set for.
  settings_ = settings;
  cfg_ = base_;
  for (size_t k = 0; k < 3; ++k) {
    mc::host::AxisLimits& a = cfg_.axes[k];
    if (!a.present) continue;
    a.max_rate_mm_s = std::min(a.max_rate_mm_s, settings.max_rate_mm_min[k] / 60.0);
    a.max_accel_mm_s2 = std::min(a.max_accel_mm_s2, settings.accel_mm_s2[k]);
  }
  if (settings.junction_deviation_mm > 0) cfg_.junction_deviation_mm = settings.junction_deviation_mm;
  if (settings.arc_tolerance_mm > 0) cfg_.arc_tolerance_mm = settings.arc_tolerance_mm;
  s_->set_config(cfg_);
  // $30/$31 map the S word to SP_PWM as the machine file's [spindle] does
  // (a range that is empty keeps the machine's).
  if (settings.spindle_min_rpm < settings.spindle_max_rpm) {
    machine_.spindle.max_rpm = settings.spindle_max_rpm;
    machine_.spindle.min_rpm = settings.spindle_min_rpm;
  }
}

bool BoardBackend::ready() const {
  return !homing_ && int(lines_.size()) + (probe_ ? 1 : 0) < blocks_;
}

void BoardBackend::arm() {
  // After a fault: clear it (BoardError while its cause is still there),
  // then arm as at the start; the command starts where the axes are.
  mc::host::clear_faults(l_);
  // Arming clears IO_CTRL; the fault that disarmed the board ended the
  // program's spindle and coolant (fault()), so they stay off until the
  // program asks again, as after a Grbl alarm.
  const mc::machine::JobBoard b = mc::machine::ready_board(l_, machine_, note_);
  s_->restart(b.at);
  lines_.clear();
  armed_ = true;
}

void BoardBackend::submit(Submission line) {
  release_wheel();
  const int key = next_key_++;
  for (gcode::CanonCall& c : line.calls) c.line = key;
  // A probe runs as its own cycle once everything before it is done; the
  // line's other calls (feed, spindle) queue before it.
  std::optional<gcode::StraightProbe> probing;
  const auto probe_call = std::find_if(line.calls.begin(), line.calls.end(), [](const gcode::CanonCall& c) {
    return std::holds_alternative<gcode::StraightProbe>(c.op);
  });
  if (probe_call != line.calls.end()) {
    probing = std::get<gcode::StraightProbe>(probe_call->op);
    line.calls.erase(probe_call);
    for (size_t k = 0; k < 3; ++k) {
      const mc::host::AxisLimits& a = cfg_.axes[k];
      const double v = probing->end[k];
      if (a.present && (v < a.min_mm - 1e-9 || v > a.max_mm + 1e-9)) {
        events_.push_back(AlarmEvent{kAlarmSoftLimit,
                                     std::string("Probe target ") + "XYZ"[k] + " " +
                                         mc::host::format_number(v) + " mm is outside the travel " +
                                         mc::host::format_number(a.min_mm) + " .. " +
                                         mc::host::format_number(a.max_mm) + " mm",
                                     false});
        return;
      }
    }
  }
  if (!armed_) {
    try {
      arm();
    } catch (const std::exception& e) {
      events_.push_back(
          AlarmEvent{kAlarmAbortCycle, std::string("Cannot arm the drives: ") + e.what(), false});
      return;
    }
  }
  std::vector<mc::host::Move> moves;
  try {
    if (levelling() && line.jog) {
      // A jog's target is the parser's, unlevelled: it ends on the bed's
      // height there (the nearest edge's off the map, which does not
      // refuse a jog), so MPos stays the program's position plus the map.
      for (gcode::CanonCall& c : line.calls)
        if (auto* f = std::get_if<gcode::StraightFeed>(&c.op))
          f->end[2] += map_->height(f->end[0], f->end[1]);
    } else if (levelling()) {
      // The program's position is the levelled end less the map under it.
      gcode::Vec3 start = s_->end();
      start[2] -= map_->height(start[0], start[1]);
      line.calls = mc::machine::level_calls(line.calls, start, *map_);
    }
    moves = mc::host::to_moves(line.calls, s_->end(), cfg_);
  } catch (const mc::host::InputError& e) {
    // Beyond the machine's travel (with $20 off; the engine checks $20 itself).
    events_.push_back(AlarmEvent{kAlarmSoftLimit, e.what(), false});
    return;
  }
  for (mc::host::Move& m : moves) m.no_override = line.jog;
  lines_.emplace_back(key, line.line_number);
  s_->append(moves);
  if (probing) probe_.emplace().op = *probing;
}

bool BoardBackend::drained() const {
  return !homing_ && !probe_ && (!armed_ || (s_->drained() && !settling_));
}

void BoardBackend::feed_hold() {
  if (armed_) s_->hold();
}

void BoardBackend::cycle_start() {
  if (armed_) s_->resume();
}

void BoardBackend::jog_cancel() {
  // Jogs run alone (the engine refuses g-code while jogging): stop them all.
  if (armed_) s_->stop();
}

void BoardBackend::soft_reset() {
  const bool cycle = homing_ || (probe_ && probe_->cycle);
  if (homing_) homing_->abort();
  if (probe_ && probe_->cycle) probe_->cycle->abort();
  homing_.reset();
  probe_.reset();
  if (cycle)
    resync();  // the cycle moved the command without the streamer
  else if (armed_)
    s_->abort();
  lines_.clear();
  settling_ = false;  // reset: Idle (or an alarm) at once, as Grbl
  spindle_off();
  read_positions();
}

void BoardBackend::spindle_off() {
  spindle_ = {};
  try {
    mc::machine::write_spindle(l_, machine_, spindle_);
  } catch (const std::runtime_error&) {
    // A link error: the board drops the outputs by itself (watchdog); the
    // next request reports the link.
  }
}

void BoardBackend::set_overrides(const Overrides& o) {
  const bool speed = o.spindle != ovr_.spindle;
  ovr_ = o;
  s_->set_overrides(o.feed / 100.0, o.rapid / 100.0);
  if (speed && spindle_.dir != 0) mc::machine::write_spindle(l_, machine_, spindle_, ovr_.spindle / 100.0);
}

void BoardBackend::fault(uint32_t bits) {
  armed_ = false;
  lines_.clear();
  const bool critical = (bits & (1u << bb::F_ESTOP)) || limit_fault(bits);
  const int code = limit_fault(bits) ? kAlarmHardLimit : kAlarmAbortCycle;
  spindle_off();
  events_.push_back(AlarmEvent{code, "Board fault: " + mc::host::fault_names(bits), critical});
}

void BoardBackend::tick() {
  if (homing_) {
    poll_homing();
  } else if (probe_ && probe_->cycle) {
    poll_probe();
  } else if (armed_) {
    try {
      s_->poll();
    } catch (const mc::host::BoardError&) {
      if (!s_->fault()) throw;  // a refused request: a bug, not the machine
      fault(s_->fault());
    }
    // The moves before a probe are done and the axes in position: probe.
    if (probe_ && s_->drained() && !settling_) poll_probe();
  }
  read_positions();
  // Lines whose moves have all run.
  const auto c = s_->current();
  if (!c) {
    lines_.clear();
  } else {
    while (!lines_.empty() && lines_.front().first < c->line) lines_.pop_front();
  }
  update_wheel();
}

std::string BoardBackend::mpg() const {
  if (!has_wheel_) return "";
  if (!mpg_.on()) return "OFF";
  return wheel_text(mpg_, "");
}

int BoardBackend::set_mpg(const std::string& selection) {
  if (!has_wheel_) return kSettingDisabled;
  mc::machine::MpgSetting s;
  try {
    s = mc::machine::parse_mpg(selection == "0" ? "off" : selection);
  } catch (const mc::host::InputError&) {
    return kInvalidStatement;
  }
  if (s.on() && (size_t(s.axis) >= machine_.axes.size() || !cfg_.axes[size_t(s.axis)].present))
    return kInvalidStatement;
  mpg_ = s;
  update_wheel();
  return 0;
}

void BoardBackend::update_wheel() {
  const bool idle = armed_ && !homing_ && !probe_ && lines_.empty() && s_->drained() && !settling_;
  if (!idle || !mpg_.on()) return release_wheel();
  if (wheel_on_ == mpg_) return;
  mc::machine::set_mpg(l_, machine_, mpg_);
  wheel_on_ = mpg_;
}

void BoardBackend::release_wheel() {
  if (!wheel_on_.on()) return;
  mc::machine::set_mpg(l_, machine_, {});
  wheel_on_ = {};
  if (armed_) s_->restart(mc::host::abort_interpolator(l_));
}

void BoardBackend::read_positions() {
  const mc::host::Vec3 cmd = s_->command_end();
  bool in = true;
  for (size_t k = 0; k < 3; ++k) {
    if (!cfg_.axes[k].present) continue;
    const int32_t c = int32_t(l_.read(br::axis(int(k), br::AX_POS)));
    pos_[k] = double(c - cfg_.axes[k].origin) / cfg_.axes[k].counts_per_mm;
    in = in && std::llabs(int64_t(c) - cmd[k]) <= kInPosition;
  }
  // The switches as the board filters them: the home switches are the
  // limit inputs (Pn:XYZ), the probe Pn:P.
  const uint32_t io = l_.read(br::IO_STAT);
  pins_.probe = io >> bb::IOS_PROBE & 1;
  for (int a = 0; a < 3; ++a) pins_.limit[a] = io >> (bb::IOS_HOME_LSB + a) & 1;
  const JobStreamer::State st = s_->state();
  if (!armed_) {
    settling_ = false;
  } else if (st != JobStreamer::State::idle && st != JobStreamer::State::held) {
    settling_ = true;
    stopped_at_.reset();
  } else if (settling_) {
    if (!stopped_at_) stopped_at_ = l_.now();
    if (in || l_.now() - *stopped_at_ > kSettleTimeout) settling_ = false;
  }
}

void BoardBackend::action(const mc::host::Move& m) {
  spindle_.apply(*m.action);
  mc::machine::write_spindle(l_, machine_, spindle_, ovr_.spindle / 100.0);
}

Status BoardBackend::status() const {
  Status s;
  const auto c = s_->current();
  s.pins = pins_;
  switch (armed_ ? s_->state() : JobStreamer::State::idle) {
    case JobStreamer::State::idle:
      s.motion = settling_ ? Motion::run : Motion::idle;
      break;
    case JobStreamer::State::run:
      s.motion = c && c->jog ? Motion::jog : Motion::run;
      break;
    case JobStreamer::State::holding:
      s.motion = Motion::holding;
      break;
    case JobStreamer::State::held:
      s.motion = settling_ ? Motion::holding : Motion::held;
      break;
  }
  if (homing_) s.motion = Motion::homing;
  if (probe_ && probe_->cycle) s.motion = Motion::run;
  if (wheel_on_.on()) s.handwheel = wheel_text(wheel_on_, ",");
  s.position = pos_;
  s.feed_mm_min = c ? c->feed_mm_s * 60 : 0;
  s.spindle = spindle_.dir;
  s.spindle_rpm = spindle_.dir ? spindle_.rpm * ovr_.spindle / 100.0 : 0;
  s.flood = spindle_.flood;
  s.mist = spindle_.mist;
  s.blocks_free = std::max(0, blocks_ - int(lines_.size()));
  if (c)
    for (const auto& [key, n] : lines_)
      if (key == c->line) s.line_number = n;
  return s;
}

std::optional<Event> BoardBackend::poll_event() {
  if (events_.empty()) return std::nullopt;
  Event e = std::move(events_.front());
  events_.pop_front();
  return e;
}

int BoardBackend::home(unsigned axis_mask) {
  release_wheel();
  if (homing_ || probe_ || !lines_.empty() || (armed_ && !s_->drained())) return kNotIdle;
  unsigned mask = 0;
  for (size_t a = 0; a < machine_.axes.size() && a < 3; ++a)
    if ((axis_mask >> a & 1) && machine_.axes[a].home) mask |= 1u << a;
  if (!mask) return kSettingDisabled;  // no switch to home on
  mc::machine::HomingPlan plan = mc::machine::homing_plan(machine_, mask);
  if (settings_) apply_homing_settings(plan, *settings_, default_settings(machine_));
  try {
    if (!armed_) {
      // After an alarm: what can be cleared is; a limit fault on a homed
      // axis the cycle clears itself, once that limit is off.
      try {
        mc::host::clear_faults(l_);
      } catch (const mc::host::BoardError&) {
      }
    }
    homing_.emplace(l_, machine_, std::move(plan), note_);
    armed_ = true;
  } catch (const mc::machine::CycleError& e) {
    cycle_failed(e.grbl_alarm(), e.what());
  } catch (const mc::host::BoardError& e) {
    cycle_failed(kAlarmAbortCycle, e.what());
  }
  return 0;
}

std::string BoardBackend::height_map() const {
  if (!map_) return "";
  using mc::host::format_number;
  return std::to_string(map_->nx) + "x" + std::to_string(map_->ny) + ",X" + format_number(map_->x0) + ".." +
         format_number(map_->x1()) + ",Y" + format_number(map_->y0) + ".." + format_number(map_->y1()) + "," +
         map_name_;
}

int BoardBackend::set_levelling(bool on) {
  if (on && !map_) return kSettingDisabled;
  level_on_ = on;
  return 0;
}

void BoardBackend::set_height_map(const mc::machine::HeightMap& map, const std::string& name) {
  map_ = map;
  map_name_ = name;
  level_on_ = true;
}

void BoardBackend::poll_homing() {
  try {
    if (!homing_->poll()) return;
  } catch (const mc::machine::CycleError& e) {
    return cycle_failed(e.grbl_alarm(), e.what());
  } catch (const mc::host::BoardError& e) {
    return cycle_failed(kAlarmAbortCycle, e.what());
  }
  homing_.reset();
  resync();  // machine zero moved: MPos and every plan from the new origin
}

void BoardBackend::poll_probe() {
  Probing& p = *probe_;
  try {
    if (!p.cycle) {
      const mc::host::Vec3 from = s_->command_end(), to = mc::host::to_counts(p.op.end, cfg_);
      const double feed = mc::machine::path_feed_counts_s(from, to, p.op.feed_mm_min, cfg_);
      const bool toward =
          p.op.mode == gcode::ProbeMode::toward || p.op.mode == gcode::ProbeMode::toward_error;
      unsigned axes = 0;
      for (size_t k = 0; k < 3; ++k)
        if (cfg_.axes[k].present) axes |= 1u << k;
      p.cycle.emplace(l_, from, to, feed, toward, axes);
    }
    if (!p.cycle->poll()) return;
  } catch (const mc::machine::CycleError& e) {
    return cycle_failed(e.grbl_alarm(), e.what());
  } catch (const mc::host::BoardError& e) {
    return cycle_failed(kAlarmAbortCycle, e.what());
  }
  events_.push_back(ProbeEvent{mc::host::to_mm(p.cycle->position(), cfg_), p.cycle->contact()});
  probe_.reset();
  resync();
}

void BoardBackend::cycle_failed(int alarm, const std::string& what) {
  homing_.reset();
  probe_.reset();
  if (const uint32_t bits = l_.read(br::FAULT)) return fault(bits);
  events_.push_back(AlarmEvent{alarm, what, false});
  resync();
}

void BoardBackend::resync() {
  base_ = mc::machine::planner_config(machine_, mc::host::read_origin(l_).counts);
  cfg_ = base_;
  if (settings_)
    configure(*settings_);
  else
    s_->set_config(cfg_);
  s_->restart(mc::host::abort_interpolator(l_));
  lines_.clear();
  read_positions();
}

}  // namespace mc::grbl
