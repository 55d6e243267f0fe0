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
constexpr int kAlarmHardLimit = 1;
constexpr int kAlarmSoftLimit = 2;
constexpr int kAlarmAbortCycle = 3;
constexpr int kAlarmProbeContact = 5;
using mc::host::kInPosition;
using mc::host::kSettleTimeout;

bool limit_fault(uint32_t bits) {
  return bits & (0x7u << bb::F_LIMIT_LSB);
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
  read_positions();
}

void BoardBackend::configure(const Settings& settings) {
  // The board's scales are its encoders': $100..$102 stay for senders. Rates
  // and accelerations apply within the machine's limits, which its motors
  // and the following-error limit were set for.
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
  return int(lines_.size()) < blocks_;
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
  const int key = next_key_++;
  for (gcode::CanonCall& c : line.calls) {
    c.line = key;
    if (std::holds_alternative<gcode::StraightProbe>(c.op)) {
      events_.push_back(AlarmEvent{kAlarmProbeContact,
                                   "Probing (G38.x) is not run on the board yet: nothing moved", false});
      return;
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
    moves = mc::host::to_moves(line.calls, s_->end(), cfg_);
  } catch (const mc::host::InputError& e) {
    // Beyond the machine's travel (with $20 off; the engine checks $20 itself).
    events_.push_back(AlarmEvent{kAlarmSoftLimit, e.what(), false});
    return;
  }
  for (mc::host::Move& m : moves) m.no_override = line.jog;
  lines_.emplace_back(key, line.line_number);
  s_->append(moves);
}

bool BoardBackend::drained() const {
  return !armed_ || (s_->drained() && !settling_);
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
  if (armed_) s_->abort();
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
  if (armed_) {
    try {
      s_->poll();
    } catch (const mc::host::BoardError&) {
      if (!s_->fault()) throw;  // a refused request: a bug, not the machine
      fault(s_->fault());
    }
  }
  read_positions();
  // Lines whose moves have all run.
  const auto c = s_->current();
  if (!c) {
    lines_.clear();
  } else {
    while (!lines_.empty() && lines_.front().first < c->line) lines_.pop_front();
  }
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

int BoardBackend::home(unsigned) {
  return kSettingDisabled;  // homing runs once the board has its cycle (issue 19)
}

}  // namespace mc::grbl
