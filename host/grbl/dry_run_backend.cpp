#include "host/grbl/dry_run_backend.hpp"

#include <algorithm>
#include <cmath>

namespace mc::grbl {
namespace {

// Integration step: short enough that a 1 mm block at 6 m/min spans ten.
constexpr double kStepS = 1e-3;
constexpr int kSettingDisabled = 5;
constexpr int kAlarmProbeInitial = 4;

double distance(const gcode::Vec3& a, const gcode::Vec3& b) {
  return std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
}

}  // namespace

DryRunBackend::DryRunBackend(int planner_blocks, gcode::Vec3 start) : blocks_(planner_blocks), pos_(start) {
  // Until configure(): a slow, gentle machine.
  settings_.max_rate_mm_min = {6000, 6000, 6000};
  settings_.accel_mm_s2 = {500, 500, 500};
}

bool DryRunBackend::ready() const {
  int used = 0;
  for (const Block& b : queue_) used += gcode::is_motion(b.call.op) ? 1 : 0;
  return used < blocks_;
}

void DryRunBackend::submit(Submission line) {
  for (const gcode::CanonCall& c : line.calls) queue_.push_back(Block{c, line.line_number, line.jog, {}, 0});
  if (keep_) received_.push_back(std::move(line));
}

bool DryRunBackend::drained() const {
  return queue_.empty();
}

void DryRunBackend::feed_hold() {
  hold_ = true;
}

void DryRunBackend::cycle_start() {
  hold_ = false;
}

void DryRunBackend::jog_cancel() {
  for (const Block& b : queue_)
    if (b.jog) cancel_ = true;
}

void DryRunBackend::soft_reset() {
  queue_.clear();
  head_started_ = hold_ = cancel_ = false;
  done_mm_ = dwell_left_ = v_ = 0;
  spindle_ = 0;
  rpm_ = 0;
  flood_ = mist_ = false;
}

void DryRunBackend::inject_fault(const AlarmEvent& alarm) {
  soft_reset();
  events_.push_back(alarm);
}

std::optional<Event> DryRunBackend::poll_event() {
  if (events_.empty()) return std::nullopt;
  Event e = std::move(events_.front());
  events_.pop_front();
  return e;
}

int DryRunBackend::home(unsigned) {
  return kSettingDisabled;  // no switches to home on
}

Status DryRunBackend::status() const {
  Status s;
  if (hold_)
    s.motion = v_ > 0 ? Motion::holding : Motion::held;
  else if (queue_.empty())
    s.motion = Motion::idle;
  else
    s.motion = queue_.front().jog ? Motion::jog : Motion::run;
  s.position = pos_;
  s.feed_mm_min = v_ * 60;
  s.spindle = spindle_;
  s.spindle_rpm = spindle_ ? rpm_ * ovr_.spindle / 100.0 : 0;
  s.flood = flood_;
  s.mist = mist_;
  int used = 0;
  for (const Block& b : queue_) used += gcode::is_motion(b.call.op) ? 1 : 0;
  s.blocks_free = std::max(0, blocks_ - used);
  s.line_number = queue_.empty() ? 0 : queue_.front().line_number;
  s.pins.probe = probe_z_ && pos_[2] <= *probe_z_;
  return s;
}

double DryRunBackend::target_speed(const Block& b) const {
  if (hold_ || cancel_) return 0;
  const double max_rate =
      *std::min_element(settings_.max_rate_mm_min.begin(), settings_.max_rate_mm_min.end());
  double f = max_rate;
  if (const auto* t = std::get_if<gcode::StraightTraverse>(&b.call.op)) {
    (void)t;
    f = max_rate * ovr_.rapid / 100.0;
  } else if (const auto* l = std::get_if<gcode::StraightFeed>(&b.call.op)) {
    f = l->feed_mm_min * (b.jog ? 1.0 : ovr_.feed / 100.0);
  } else if (const auto* a = std::get_if<gcode::ArcFeed>(&b.call.op)) {
    f = a->feed_mm_min * ovr_.feed / 100.0;
  } else if (const auto* p = std::get_if<gcode::StraightProbe>(&b.call.op)) {
    f = p->feed_mm_min;  // Grbl: no feed override while probing
  }
  return std::min(f, max_rate) / 60.0;
}

gcode::Vec3 DryRunBackend::point(const Block& b, double s) const {
  const double f = b.length > 0 ? std::clamp(s / b.length, 0.0, 1.0) : 1.0;
  if (const auto* a = std::get_if<gcode::ArcFeed>(&b.call.op)) {
    if (f >= 1) return a->end;
    const gcode::PlaneAxes ax = gcode::plane_axes(a->plane);
    const auto i = size_t(ax.first), j = size_t(ax.second), n = size_t(ax.normal);
    const double r0 = std::hypot(b.start[i] - a->centre[i], b.start[j] - a->centre[j]);
    const double r1 = std::hypot(a->end[i] - a->centre[i], a->end[j] - a->centre[j]);
    const double th0 = std::atan2(b.start[j] - a->centre[j], b.start[i] - a->centre[i]);
    const double th = th0 + (a->clockwise ? -1 : 1) * gcode::arc_sweep(b.start, *a) * f;
    const double r = r0 + (r1 - r0) * f;
    gcode::Vec3 p{};
    p[i] = a->centre[i] + r * std::cos(th);
    p[j] = a->centre[j] + r * std::sin(th);
    p[n] = b.start[n] + (a->end[n] - b.start[n]) * f;
    return p;
  }
  gcode::Vec3 end = b.start;
  if (const auto* t = std::get_if<gcode::StraightTraverse>(&b.call.op)) end = t->end;
  if (const auto* l = std::get_if<gcode::StraightFeed>(&b.call.op)) end = l->end;
  if (const auto* p = std::get_if<gcode::StraightProbe>(&b.call.op)) end = p->end;
  gcode::Vec3 p{};
  for (size_t k = 0; k < 3; ++k) p[k] = b.start[k] + (end[k] - b.start[k]) * f;
  return p;
}

void DryRunBackend::begin(Block& b) {
  head_started_ = true;
  done_mm_ = 0;
  b.start = pos_;
  b.length = 0;
  if (const auto* t = std::get_if<gcode::StraightTraverse>(&b.call.op)) b.length = distance(pos_, t->end);
  if (const auto* l = std::get_if<gcode::StraightFeed>(&b.call.op)) b.length = distance(pos_, l->end);
  if (const auto* a = std::get_if<gcode::ArcFeed>(&b.call.op)) b.length = gcode::arc_length(pos_, *a);
  if (const auto* d = std::get_if<gcode::Dwell>(&b.call.op)) {
    dwell_left_ = d->seconds;
    v_ = 0;  // a dwell is a stop
  }
  if (const auto* p = std::get_if<gcode::StraightProbe>(&b.call.op)) {
    b.length = distance(pos_, p->end);
    const bool toward = p->mode == gcode::ProbeMode::toward || p->mode == gcode::ProbeMode::toward_error;
    const bool pin = probe_z_ && pos_[2] <= *probe_z_;
    if (pin == toward) {
      // Grbl's ALARM:4: the probe is already in the state the move looks for.
      soft_reset();
      events_.push_back(AlarmEvent{kAlarmProbeInitial, "", false});
    }
  }
}

void DryRunBackend::finish_head() {
  const Block b = queue_.front();
  queue_.pop_front();
  head_started_ = false;
  done_mm_ = 0;
  if (const auto* s = std::get_if<gcode::StartSpindle>(&b.call.op)) {
    spindle_ = s->clockwise ? 1 : -1;
    rpm_ = s->rpm;
  } else if (std::holds_alternative<gcode::StopSpindle>(b.call.op)) {
    spindle_ = 0;
  } else if (const auto* r = std::get_if<gcode::SetSpindleSpeed>(&b.call.op)) {
    rpm_ = r->rpm;
  } else if (const auto* c = std::get_if<gcode::SetCoolant>(&b.call.op)) {
    flood_ = c->flood;
    mist_ = c->mist;
  } else if (const auto* e = std::get_if<gcode::ProgramStop>(&b.call.op)) {
    if (e->kind == gcode::StopKind::end || e->kind == gcode::StopKind::end_rewind) {
      spindle_ = 0;
      flood_ = mist_ = false;
    }
  }
}

double DryRunBackend::travel(double dist) {
  while (!queue_.empty()) {
    if (!head_started_) begin(queue_.front());
    if (queue_.empty()) return 0;  // begin() refused a probe
    Block& b = queue_.front();
    if (std::holds_alternative<gcode::Dwell>(b.call.op)) return 0;  // runs on the clock
    if (!moves(b)) {
      if (const auto* p = std::get_if<gcode::StraightProbe>(&b.call.op))
        events_.push_back(ProbeEvent{p->end, false});
      finish_head();
      continue;
    }
    if (dist <= 0) return 0;
    const double to = std::min(b.length, done_mm_ + dist);
    if (const auto* p = std::get_if<gcode::StraightProbe>(&b.call.op)) {
      const bool toward = p->mode == gcode::ProbeMode::toward || p->mode == gcode::ProbeMode::toward_error;
      const gcode::Vec3 a = point(b, done_mm_), c = point(b, to);
      if (probe_z_ && (toward ? c[2] <= *probe_z_ : c[2] > *probe_z_) && c[2] != a[2]) {
        // The input changed within this step: stop where it did.
        const double s = done_mm_ + (to - done_mm_) * (*probe_z_ - a[2]) / (c[2] - a[2]);
        pos_ = point(b, s);
        v_ = 0;
        events_.push_back(ProbeEvent{pos_, true});
        finish_head();
        return 0;
      }
      if (to >= b.length) events_.push_back(ProbeEvent{p->end, false});
    }
    dist -= to - done_mm_;
    done_mm_ = to;
    pos_ = point(b, done_mm_);
    if (done_mm_ < b.length) return 0;
    finish_head();
  }
  return dist;
}

void DryRunBackend::advance(double dt_s) {
  while (dt_s > 0) {
    const double h = std::min(dt_s, kStepS);
    dt_s -= h;
    time_s_ += h;
    travel(0);  // start what does not move (spindle, coolant, dwells, empty moves)
    if (queue_.empty()) {
      v_ = 0;
      cancel_ = false;
      continue;
    }
    if (std::holds_alternative<gcode::Dwell>(queue_.front().call.op)) {
      if (hold_) continue;
      dwell_left_ -= h;
      if (dwell_left_ <= 0) finish_head();
      continue;
    }
    const double accel = *std::min_element(settings_.accel_mm_s2.begin(), settings_.accel_mm_s2.end());
    const double target = target_speed(queue_.front());
    v_ = v_ < target ? std::min(target, v_ + accel * h) : std::max(target, v_ - accel * h);
    if (v_ == 0 && cancel_) {
      queue_.erase(std::remove_if(queue_.begin(), queue_.end(), [](const Block& b) { return b.jog; }),
                   queue_.end());
      head_started_ = false;
      done_mm_ = 0;
      cancel_ = false;
      continue;
    }
    travel(v_ * h);
    if (queue_.empty()) v_ = 0;  // the last block ended: the machine stands
  }
}

}  // namespace mc::grbl
