#include "host/machine/cycles.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/job.hpp"
#include "host/motion/board_run.hpp"

namespace mc::machine {

namespace br = board::reg;
namespace bb = board::bits;
using mc::host::BoardLink;
using mc::host::Vec3;

namespace {

constexpr int kAlarmProbeInitial = 4;
constexpr int kAlarmPullOff = 8;
constexpr int kAlarmNotFound = 9;

// Grbl's HOMING_AXIS_SEARCH_SCALAR and HOMING_AXIS_LOCATE_SCALAR.
constexpr double kSearchScale = 1.5;
constexpr double kLocateScale = 5.0;

std::string axis_letter(int a) {
  return std::string(1, "XYZ"[a]);
}

// LATCH: `axes` latch on the source and stop the interpolator; the others
// (every axis with Source::none) latch on nothing.
uint32_t latch_word(LatchedMove::Source src, unsigned axes, bool probe_inv) {
  if (src == LatchedMove::Source::none) axes = 0;
  const uint32_t on = src == LatchedMove::Source::home ? bb::L_SRC_HOME : bb::L_SRC_PROBE;
  uint32_t v = axes ? 1u << bb::L_STOP : 0;
  for (int a = 0; a < 3; ++a) v |= (axes >> a & 1 ? on : bb::L_SRC_NONE) << (bb::L_SRC_LSB + 2 * a);
  return probe_inv ? v | 1u << bb::L_PROBE_INV : v;
}

}  // namespace

void wait_on_link(BoardLink& l) {
  l.poll(std::chrono::milliseconds(1));
}

double path_feed_counts_s(const Vec3& from, const Vec3& to, double feed_mm_min,
                          const mc::host::PlannerConfig& cfg) {
  double mm2 = 0, counts2 = 0;
  for (size_t k = 0; k < 3; ++k) {
    const double d = double(to[k] - from[k]);
    if (cfg.axes[k].present) mm2 += std::pow(d / cfg.axes[k].counts_per_mm, 2);
    counts2 += d * d;
  }
  const double len_mm = std::sqrt(mm2);
  if (!(len_mm > 0)) return 0;
  double v = feed_mm_min / 60;
  for (size_t k = 0; k < 3; ++k) {
    const mc::host::AxisLimits& a = cfg.axes[k];
    const double d_mm = a.present ? std::fabs(double(to[k] - from[k])) / a.counts_per_mm : 0;
    if (d_mm > 0) v = std::min(v, a.max_rate_mm_s * len_mm / d_mm);
  }
  return std::sqrt(counts2) / len_mm * v;
}

bool probe_closed(BoardLink& l) {
  return l.read(br::IO_STAT) >> bb::IOS_PROBE & 1;
}

// ---- LatchedMove -------------------------------------------------------------

LatchedMove::LatchedMove(BoardLink& l, const Spec& s) : l_(l), s_(s), end_(s.from) {
  for (int a = 0; a < 3; ++a)
    if (s.to[size_t(a)] != s.from[size_t(a)]) s_.moving_axes |= 1u << a;
  l_.write(br::LATCH, latch_word(s.source, s.latch_axes, s.probe_inv));
  if (s.source != Source::none)
    for (int a = 0; a < 3; ++a)
      if (s.latch_axes >> a & 1) l_.write(br::axis(a, br::AX_IDX), 1u << bb::X_ARM);
  segs0_ = l_.read(br::IP_SEGS) & 0xFFFF;
  if (s.to != s.from && s.feed_counts_s > 0)
    segs_ = mc::host::plan_move(s.from, s.to, s.feed_counts_s, double(l_.read(br::CLK_HZ)));
}

bool LatchedMove::poll() {
  if (done_) return true;
  const uint32_t fault = l_.read(br::FAULT);
  if (fault) throw mc::host::BoardError("motion stopped by a fault: " + mc::host::fault_names(fault));
  const auto seen = [&] {
    unsigned v = 0;
    if (s_.source != Source::none)
      for (int a = 0; a < 3; ++a)
        if ((s_.latch_axes >> a & 1) && (l_.read(br::axis(a, br::AX_ENC_STAT)) >> bb::ES_IDX_SEEN & 1))
          v |= 1u << a;
    return v;
  };
  if (!settling_) {
    const unsigned got = seen();
    // Nothing more goes out once a latch stopped the interpolator: what the
    // stop flushed must not run after it.
    if (!got) sent_ = mc::host::send_segments(l_, segs_, sent_);
    const uint32_t ip = l_.read(br::IP_STAT);
    const bool busy = ip >> bb::IS_BUSY & 1, queued = (ip & 0xFFFF) != 0;
    const size_t done = (l_.read(br::IP_SEGS) - segs0_) & 0xFFFF;
    if (got) {
      if (busy || queued) return false;
      end_ = mc::host::abort_interpolator(l_);
    } else if (sent_ < segs_.size() || done < segs_.size() || busy) {
      return false;
    } else {
      end_ = segs_.empty() ? s_.from : s_.to;
    }
    settling_ = true;
    settle_until_ = l_.now() + mc::host::kSettleTimeout;
  }
  // The axes catch up with the stopped command before anything is judged:
  // a servo runs behind its command, and an axis whose switch it reaches
  // while catching up latches then, not during the move.
  bool in = true;
  for (int a = 0; a < 3; ++a)
    if (s_.moving_axes >> a & 1)
      in = in && std::abs(int32_t(l_.read(br::axis(a, br::AX_FOLLOW)))) <= mc::host::kInPosition;
  if (!in && l_.now() < settle_until_) return false;
  latched_ = seen();
  for (int a = 0; a < 3; ++a)
    if (latched_ >> a & 1) latch_pos_[size_t(a)] = int32_t(l_.read(br::axis(a, br::AX_IDX)));
  if (s_.source != Source::none) l_.write(br::LATCH, latch_word(Source::none, 0, false));
  done_ = true;
  return true;
}

// ---- homing ------------------------------------------------------------------

HomingPlan homing_plan(const MachineConfig& m, unsigned mask) {
  HomingPlan p;
  std::vector<HomeAxis> axes;
  for (int a = 0; a < int(m.axes.size()) && a < 3; ++a) {
    if (!(mask >> a & 1)) continue;
    const AxisConfig& ax = m.axes[size_t(a)];
    if (!ax.home)
      throw mc::host::InputError("axis " + ax.name, "without [axis." + ax.name + ".home] in " + m.source,
                                 "a home switch to home on", "no switch is described for it");
    const HomeConfig& h = *ax.home;
    HomeAxis x;
    x.axis = a;
    x.direction = h.direction;
    x.switch_mm = h.switch_m * 1e3;
    x.seek_mm_min = h.seek_m_s * 60e3;
    x.locate_mm_min = h.locate_m_s * 60e3;
    x.pull_off_mm = h.pull_off_m * 1e3;
    x.order = h.order;
    axes.push_back(x);
    p.search_mm[a] = kSearchScale * (ax.travel_max_m - ax.travel_min_m) * 1e3;
  }
  std::stable_sort(axes.begin(), axes.end(),
                   [](const HomeAxis& x, const HomeAxis& y) { return x.order < y.order; });
  for (const HomeAxis& x : axes) {
    if (p.passes.empty() || p.passes.back().front().order != x.order) p.passes.emplace_back();
    p.passes.back().push_back(x);
  }
  return p;
}

HomingCycle::HomingCycle(BoardLink& l, const MachineConfig& m, HomingPlan plan, const mc::host::Note& note)
    : l_(l), m_(m), plan_(std::move(plan)) {
  safety0_ = l_.read(br::SAFETY);
  latch0_ = l_.read(br::LATCH);
  unsigned mask = 0;
  for (const auto& pass : plan_.passes)
    for (const HomeAxis& x : pass) mask |= 1u << x.axis;
  // The switches are the limit inputs: the cycle runs onto them on purpose,
  // and an axis that stands on its switch (its limit fault latched at
  // power-up) may arm once that limit is off.
  l_.write(br::SAFETY, safety0_ & ~(mask << bb::S_LIM_EN_LSB));
  const uint32_t fault = l_.read(br::FAULT) & (mask << bb::F_LIMIT_LSB);
  if (fault) l_.write(br::FAULT, fault);
  try {
    ready_board(l_, m_, note);
  } catch (...) {
    restore();
    throw;
  }
  mc::host::clear_homed(l_, mask);
  at_ = mc::host::abort_interpolator(l_);
  if (plan_.passes.empty())
    phase_ = Phase::done;
  else
    start_phase(Phase::clear);
}

double HomingCycle::cpmm(int a) const {
  return counts_per_m(m_.axes[size_t(a)]) * 1e-3;
}

bool HomingCycle::switch_closed(int a) {
  return l_.read(br::IO_STAT) >> (bb::IOS_HOME_LSB + a) & 1;
}

void HomingCycle::start_move(const std::vector<const HomeAxis*>& axes, int sign, Reach reach, bool locate,
                             LatchedMove::Source src) {
  const auto distance_mm = [&](const HomeAxis& x) {
    switch (reach) {
      case Reach::search:
        return plan_.search_mm[x.axis];
      case Reach::locate:
        return kLocateScale * x.pull_off_mm;
      case Reach::pull_off:
        break;
    }
    return x.pull_off_mm;
  };
  const auto speed_mm_s = [&](const HomeAxis& x) {
    return (locate ? x.locate_mm_min : x.seek_mm_min) / 60.0;
  };
  // Each axis at its own speed: distances in proportion to the speeds make
  // one straight line on which every axis keeps its rate, for as long as
  // the slowest needs to cover its distance.
  double t = 0;
  for (const HomeAxis* x : axes) t = std::max(t, distance_mm(*x) / speed_mm_s(*x));
  LatchedMove::Spec s;
  s.from = s.to = at_;
  s.source = src;
  double len2 = 0;
  for (const HomeAxis* x : axes) {
    const double counts = sign * x->direction * speed_mm_s(*x) * t * cpmm(x->axis);
    s.to[size_t(x->axis)] += int64_t(std::llround(counts));
    s.latch_axes |= 1u << x->axis;
    len2 += counts * counts;
  }
  s.feed_counts_s = t > 0 ? std::sqrt(len2) / t : 0;
  move_.emplace(l_, s);
}

void HomingCycle::start_phase(Phase p) {
  phase_ = p;
  std::vector<const HomeAxis*> axes;
  const auto& pass = plan_.passes[pass_];
  switch (p) {
    case Phase::clear:
      // An axis standing on its switch backs off first: the latch takes the
      // switch's closing edge, which it would never see.
      for (const HomeAxis& x : pass)
        if (switch_closed(x.axis)) axes.push_back(&x);
      pending_ = 0;
      for (const HomeAxis& x : pass) pending_ |= 1u << x.axis;
      if (axes.empty()) return start_phase(Phase::seek);
      start_move(axes, -1, Reach::locate, false, LatchedMove::Source::none);
      return;
    case Phase::seek:
    case Phase::locate:
      for (const HomeAxis& x : pass)
        if (pending_ >> x.axis & 1) axes.push_back(&x);
      if (p == Phase::seek)
        start_move(axes, +1, Reach::search, false, LatchedMove::Source::home);
      else
        start_move(axes, +1, Reach::locate, true, LatchedMove::Source::home);
      return;
    case Phase::pull_off:
    case Phase::park:
      for (const HomeAxis& x : pass) axes.push_back(&x);
      start_move(axes, -1, Reach::pull_off, false, LatchedMove::Source::none);
      return;
    case Phase::done:
      return;
  }
}

void HomingCycle::fail(int alarm, const std::string& what) {
  restore();
  throw CycleError(alarm, what);
}

void HomingCycle::restore() {
  if (restored_) return;
  restored_ = true;
  l_.write(br::LATCH, latch0_);
  l_.write(br::SAFETY, safety0_);
}

void HomingCycle::abort() {
  if (phase_ == Phase::done) return;
  phase_ = Phase::done;
  mc::host::abort_interpolator(l_);
  restore();
}

bool HomingCycle::poll() {
  if (phase_ == Phase::done) return true;
  try {
    if (!move_->poll()) return false;
  } catch (...) {
    restore();
    throw;
  }
  at_ = move_->end();
  const auto& pass = plan_.passes[pass_];
  Phase next = phase_;
  switch (phase_) {
    case Phase::clear:
    case Phase::pull_off:
      // Grbl's ALARM:8: the latch needs the switch's closing edge.
      for (const HomeAxis& x : pass)
        if (switch_closed(x.axis))
          fail(kAlarmPullOff,
               "homing: the " + axis_letter(x.axis) + " switch stayed closed after backing off " +
                   mc::host::format_number(phase_ == Phase::clear ? x.pull_off_mm * kLocateScale
                                                                  : x.pull_off_mm) +
                   " mm");
      for (const HomeAxis& x : pass) pending_ |= 1u << x.axis;
      next = phase_ == Phase::clear ? Phase::seek : Phase::locate;
      break;
    case Phase::seek:
    case Phase::locate: {
      const unsigned got = move_->latched() & pending_;
      if (!got) {
        std::string names;
        for (const HomeAxis& x : pass)
          if (pending_ >> x.axis & 1) names += axis_letter(x.axis);
        fail(kAlarmNotFound, std::string("homing: no switch on ") + names + " within " +
                                 (phase_ == Phase::seek ? "the search distance (1.5 x the travel)"
                                                        : "the locate distance (5 x the pull-off)"));
      }
      for (int a = 0; a < 3; ++a)
        if (got >> a & 1) latch_[size_t(a)] = move_->latch_position()[size_t(a)];
      pending_ &= ~got;
      if (pending_) {
        next = phase_;  // the others go on from where the latch stopped them
      } else if (phase_ == Phase::seek) {
        next = Phase::pull_off;
      } else {
        for (const HomeAxis& x : pass) {
          origin_[size_t(x.axis)] =
              latch_[size_t(x.axis)] - int64_t(std::llround(x.switch_mm * cpmm(x.axis)));
          mc::host::write_origin(l_, x.axis, origin_[size_t(x.axis)]);
        }
        next = Phase::park;
      }
      break;
    }
    case Phase::park:
      if (++pass_ >= plan_.passes.size()) {
        restore();
        phase_ = Phase::done;
        return true;
      }
      next = Phase::clear;
      break;
    case Phase::done:
      break;
  }
  start_phase(next);
  return false;
}

Vec3 home_axes(BoardLink& l, const MachineConfig& m, unsigned mask, const mc::host::Note& note) {
  HomingCycle c(l, m, homing_plan(m, mask), note);
  while (!c.poll()) wait_on_link(l);
  return c.origin();
}

// ---- probing -----------------------------------------------------------------

namespace {
LatchedMove::Spec probe_spec(const Vec3& from, const Vec3& to, double feed, bool toward, unsigned axes) {
  LatchedMove::Spec s;
  s.from = from;
  s.to = to;
  s.feed_counts_s = feed;
  s.source = LatchedMove::Source::probe;
  s.latch_axes = axes;
  s.probe_inv = !toward;
  return s;
}
}  // namespace

ProbeCycle::ProbeCycle(BoardLink& l, const Vec3& from, const Vec3& to, double feed, bool toward,
                       unsigned axes)
    : l_(l), latch0_(l.read(br::LATCH)), move_(l, probe_spec(from, to, feed, toward, axes)) {
  // LATCH (the probe's inversion with it) went out a link round trip before
  // the latches were armed: the filter had settled, so a probe already in
  // the state the move looks for latched nothing, and shows here, before a
  // segment is sent. Grbl's ALARM:4.
  if (probe_closed(l_)) {
    abort();
    throw CycleError(kAlarmProbeInitial, toward ? "probe: already touching before the move"
                                                : "probe: not touching before a move away from contact");
  }
}

bool ProbeCycle::poll() {
  try {
    if (!move_.poll()) return false;
  } catch (...) {
    abort();
    throw;
  }
  if (!restored_) {
    restored_ = true;
    l_.write(br::LATCH, latch0_);
  }
  return true;
}

void ProbeCycle::abort() {
  if (restored_) return;
  restored_ = true;
  mc::host::abort_interpolator(l_);
  l_.write(br::LATCH, latch0_);
}

}  // namespace mc::machine
