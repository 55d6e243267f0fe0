#include "sim/plant/dc_motor.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include "host/base/errors.hpp"

namespace mc::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int32_t kFullScale = 32767;

int32_t saturate(int32_t u) {
  return std::clamp(u, -kFullScale, kFullScale);
}

// floor(v / 2^s) for v >= -2^31, without relying on how >> treats negatives.
int32_t floor_shift(int32_t v, int s) {
  return v >= 0 ? v >> s : -int32_t((uint32_t(-int64_t(v)) + (uint32_t(1) << s) - 1) >> s);
}

}  // namespace

AxisPlant::AxisPlant(const AxisConfig& cfg, double dt_s) : m_(cfg.motor), dt_(dt_s) {
  if (!(dt_s > 0) || !std::isfinite(dt_s)) {
    throw mc::host::InputError("plant dt", mc::host::format_number(dt_s), "a finite step > 0 s");
  }
  j_ = m_.j_kg_m2 + reflected_inertia_kg_m2(cfg);
  tau_load_ = reflected_torque_nm(cfg);
  rad_to_m_ = cfg.lead_m_per_rev / (2 * kPi * cfg.gear_ratio);
  rad_to_count_ = cfg.encoder_cpr / (2 * kPi);

  // Zero-order hold, exactly: exp([[A, Bc], [0, 0]] dt) = [[Ad, Bd], [0, I]].
  Eigen::Matrix<double, 5, 5> mc = Eigen::Matrix<double, 5, 5>::Zero();
  mc(0, 0) = -m_.r_ohm / m_.l_h;
  mc(0, 1) = -m_.ke_v_s_per_rad / m_.l_h;
  mc(1, 0) = m_.kt_nm_per_a / j_;
  mc(1, 1) = -m_.b_nm_s_per_rad / j_;
  mc(2, 1) = 1;
  mc(0, 3) = 1 / m_.l_h;  // input V
  mc(1, 4) = -1 / j_;     // input tau_ext, opposing +w
  const Eigen::Matrix<double, 5, 5> e = (mc * dt_s).exp();
  // With w held at 0 only the electrical equation remains: i(k+1) = a i(k)
  // + b V, a = exp(-R dt/L), b = (1 - a)/R.
  pw_ = powers_for(e.topLeftCorner<3, 3>(), e.topRightCorner<3, 2>(), std::exp(-m_.r_ohm / m_.l_h * dt_s),
                   -std::expm1(-m_.r_ohm / m_.l_h * dt_s) / m_.r_ohm);
  // The speed under a held input is a constant plus two exponentials of the
  // electromechanical poles; with real poles its derivative has at most one
  // zero, which is what hold()'s search needs (complex poles: step by step).
  const double tr = m_.r_ohm / m_.l_h + m_.b_nm_s_per_rad / j_;
  const double det = (m_.r_ohm * m_.b_nm_s_per_rad + m_.ke_v_s_per_rad * m_.kt_nm_per_a) / (m_.l_h * j_);
  monotone_runs_ = tr * tr - 4 * det >= 0;
}

std::shared_ptr<const AxisPlant::Powers> AxisPlant::powers_for(const Eigen::Matrix3d& ad_1,
                                                               const Eigen::Matrix<double, 3, 2>& bd_1,
                                                               double stuck_a, double stuck_b) {
  // Axes of one machine are often alike, and a machine is built again for
  // every run: the tables of a discretization already built are shared
  // while a plant holds them (the key is the exact one-step matrices).
  static std::mutex mu;
  static std::vector<std::weak_ptr<const Powers>> built;
  const std::lock_guard<std::mutex> lock(mu);
  for (auto it = built.begin(); it != built.end();) {
    if (std::shared_ptr<const Powers> p = it->lock()) {
      if (p->ad_1 == ad_1 && p->bd_1 == bd_1 && p->stuck_a_1 == stuck_a && p->stuck_b_1 == stuck_b) return p;
      ++it;
    } else {
      it = built.erase(it);
    }
  }
  auto pw = std::make_shared<Powers>();
  pw->ad_1 = ad_1;
  pw->bd_1 = bd_1;
  pw->stuck_a_1 = stuck_a;
  pw->stuck_b_1 = stuck_b;
  pw->k = std::make_unique_for_overwrite<Power[]>(kRun + 1);
  pw->stuck_a = std::make_unique_for_overwrite<double[]>(kRun + 1);
  pw->stuck_b = std::make_unique_for_overwrite<double[]>(kRun + 1);
  built.push_back(pw);
  return pw;
}

uint32_t AxisPlant::Powers::fill_to(uint32_t step) const {
  for (uint32_t c = 0; c < kChunks; ++c) {
    const uint32_t from = c == 0 ? 0 : kChunkEnd[c - 1], to = kChunkEnd[c];
    // Each step from the one before, the powers read back from the table
    // as the loop left them: the same figures whatever the chunks.
    std::call_once(filled[c], [&] {
      Eigen::Matrix3d ad = Eigen::Matrix3d::Identity();
      Eigen::Matrix<double, 3, 2> bd = Eigen::Matrix<double, 3, 2>::Zero();
      double sa = 1, sb = 0;
      const auto next = [&] {  // one step on
        bd = bd + ad * bd_1;
        ad = ad_1 * ad;
        sb = sb + sa * stuck_b_1;
        sa = stuck_a_1 * sa;
      };
      if (from > 0) {
        const Power& p = k[from - 1];
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) ad(i, j) = p.ad[i][j];
          for (int j = 0; j < 2; ++j) bd(i, j) = p.bd[i][j];
        }
        sa = stuck_a[from - 1];
        sb = stuck_b[from - 1];
        next();
      }
      for (uint32_t j = from; j < to; ++j) {
        Power& p = k[j];
        for (int r = 0; r < 3; ++r) {
          for (int q = 0; q < 3; ++q) p.ad[r][q] = ad(r, q);
          for (int q = 0; q < 2; ++q) p.bd[r][q] = bd(r, q);
        }
        stuck_a[j] = sa;
        stuck_b[j] = sb;
        next();
      }
    });
    if (step < to) return to;
  }
  throw std::logic_error("plant: step " + std::to_string(step) + " of a run, past the tables' " +
                         std::to_string(kRun));
}

void AxisPlant::anchor(double v, double dir) {
  x0_ = x_;
  v_ = v;
  dir_ = dir;
  k_ = 0;
  ++runs_;
  anchored_ = true;
  u0_ = Eigen::Vector2d(v, tau_load_ + (friction_ && !stuck_ ? dir * m_.coulomb_nm : 0.0));
}

double AxisPlant::driving_torque_nm() const {
  return m_.kt_nm_per_a * x_(0) - tau_load_;
}

void AxisPlant::step(double v) {
  ++steps_;
  if (!in_run(v)) anchor(v, x_(1) > 0 ? 1.0 : -1.0);
  reach(k_ + 1);
  if (friction_ && stuck_) {
    const double drive = driving_torque_nm();
    if (std::fabs(drive) <= m_.stiction_nm) {
      x_(0) = run_stuck_current(++k_);  // w and theta stay exactly where they are
      return;
    }
    stuck_ = false;  // breakaway, in the direction of the driving torque
    anchor(v, drive > 0 ? 1.0 : -1.0);
  }
  moving_step();
}

void AxisPlant::moving_step() {
  // Coulomb friction opposes the motion for the whole step (the run's input).
  // (Its callers reached the step: step() and hold_through()'s search.)
  x_ = run_state(++k_);
  // Friction can stop the shaft, never reverse it: a step that would cross
  // zero speed ends at rest, and the stiction test decides what comes next.
  if (friction_ && x_(1) * dir_ <= 0) {
    x_(1) = 0;
    stuck_ = true;
    anchor(v_, 0);
  }
}

uint64_t AxisPlant::hold(double v, uint64_t n) {
  Samples none;
  return hold(v, n, none);
}

uint64_t AxisPlant::hold(double v, uint64_t n, Samples& samples) {
  return hold_through(v, n, samples, nullptr, 0).steps;
}

AxisPlant::Held AxisPlant::hold_counting(double v, uint64_t n, Samples& samples,
                                         std::vector<CountChange>& changes, uint64_t step0) {
  return hold_through(v, n, samples, &changes, step0);
}

AxisPlant::Held AxisPlant::hold_through(double v, uint64_t n, Samples& samples,
                                        std::vector<CountChange>* changes, uint64_t step0) {
  int64_t count = encoder_count();
  uint64_t taken = 0;
  uint64_t next = samples.out ? samples.first : n + 1;  // the next sampled step of the call
  // The trace's slots for the next `records` sampled steps, its room
  // checked once; next moves past them.
  const auto take = [&](uint64_t records) {
    if (samples.room < records) throw std::logic_error("plant hold: more samples than room for them");
    double* const at = samples.out;
    samples.out += records;
    samples.room -= records;
    next += records * samples.every;
    return at;
  };
  // The pieces of the run the search is in, found once per run: a count
  // change goes on in the same run, up to the same last step (k_ and
  // taken move together), so the pieces from its start still hold.
  Pieces cut{};
  uint64_t cut_run = 0;
  bool cut_set = false;
  bool big = false;
  while (taken < n) {
    bool moving = false;  // searched a moving run: the next step is in it
    // A stretch of a step or two is taken by step(): cheaper than a search.
    // A longer one on a new input starts its run here, as step() would (the
    // search then covers its first step too).
    if (monotone_runs_ && n - taken >= kSearchFrom) {
      if (!in_run(v)) anchor(v, x_(1) > 0 ? 1.0 : -1.0);
      const uint32_t lim = uint32_t(std::min<uint64_t>(n - taken, kRun - k_));
      reach(k_ + lim);
      const bool stuck = friction_ && stuck_;
      uint32_t quiet;
      if (stuck) {
        quiet = steps_before_breakaway(lim);
      } else {
        if (!cut_set || cut_run != runs_) {
          cut = pieces(k_, k_ + lim);
          cut_run = runs_;
          cut_set = true;
        }
        quiet = steps_before_event(cut, count);
      }
      if (quiet > 0 && next <= taken + quiet) {
        // Samples inside the quiet stretch, from the run (a stuck shaft
        // stands where it is).
        const uint64_t records = (taken + quiet - next) / samples.every + 1;
        const uint32_t k = uint32_t(k_ + (next - taken));
        double* const out = take(records);
        if (stuck)
          std::fill_n(out, records, position_m());
        else
          run_positions(k, uint32_t(samples.every), records, out);
      }
      if (quiet > 0) {
        k_ += quiet;
        steps_ += quiet;
        taken += quiet;
        if (stuck)
          x_(0) = run_stuck_current(k_);
        else if (quiet == lim)
          x_ = run_state(k_);  // else the event's step sets it
        if (quiet == lim) continue;
      }
      moving = !stuck;
    }
    // The step with the event (or the first of a new run): as step() does
    // it. In a moving run that is moving_step(), which does not read the
    // state a quiet stretch left unset.
    if (moving) {
      ++steps_;
      moving_step();
    } else {
      step(v);
    }
    ++taken;
    if (next == taken) *take(1) = position_m();
    if (const int64_t now = encoder_count(); now != count) {
      if (!changes) break;
      changes->push_back(CountChange{step0 + taken, now});
      big = now - count > 1 || now - count < -1;
      count = now;
      if (big) break;
    }
  }
  if (samples.out) samples.first = next - taken;
  return Held{taken, big};
}

namespace {

int sign_of(double v) {
  return (v > 0) - (v < 0);
}

// The last j in [lo, hi] with sign_of(f(j)) == sign_of(f(lo)), for an f whose
// sign changes at most once on [lo, hi].
template <typename F>
uint32_t last_of_sign(uint32_t lo, uint32_t hi, F f) {
  const int s = sign_of(f(lo));
  if (s == 0 || sign_of(f(hi)) == s) return hi;
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    (sign_of(f(mid)) == s ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

AxisPlant::Pieces AxisPlant::pieces(uint32_t lo, uint32_t hi) const {
  const auto accel = [&](uint32_t j) {
    return m_.kt_nm_per_a * run_x(j, 0) - m_.b_nm_s_per_rad * run_x(j, 1) - u0_(1);
  };
  const auto speed = [&](uint32_t j) { return run_x(j, 1); };
  // Pieces of the run on which the speed is monotone (split where the
  // acceleration changes sign) and, without friction, of one sign (split
  // where it crosses zero): on each the angle is monotone too, so once an
  // event holds it holds to the piece's end, and a bisection finds the first.
  Pieces p{};
  // With friction the events are monotone over the whole run unless the
  // shaft first slows down and then speeds up again (speed changes sign
  // at most once): speeding up first, its speed is least at the run's
  // ends, so it moves one way until friction stops it, if it does; slowing
  // down throughout, likewise. Only the dip needs its turn found.
  if (friction_) {
    const double a0 = accel(lo) * dir_;
    if (a0 >= 0 || accel(hi) * dir_ < 0) {
      p.cut[p.n++] = hi;
      return p;
    }
  }
  const uint32_t turn = last_of_sign(lo, hi, accel);
  const auto piece = [&](uint32_t a, uint32_t b) {
    const uint32_t cross = friction_ ? b : last_of_sign(a, b, speed);
    if (cross != b) p.cut[p.n++] = cross;
    p.cut[p.n++] = b;
  };
  piece(lo, turn);
  if (turn < hi) piece(turn + 1, hi);
  return p;
}

uint32_t AxisPlant::steps_before_event(const Pieces& p, int64_t count) const {
  uint32_t from = k_;  // no event here
  for (int i = 0; i < p.n; ++i) {
    const uint32_t to = p.cut[i];
    if (to <= from) continue;
    // The speed is monotone over the piece and of the motion's sign at
    // `from`: friction can stop the shaft inside only if it has at `to`.
    const bool stops = friction_ && run_x(to, 1) * dir_ <= 0;
    if (stops || count_at(run_x(to, 2)) != count) return first_event(from, to, count, stops) - 1 - k_;
    from = to;
  }
  return p.cut[p.n - 1] - k_;
}

uint32_t AxisPlant::first_event(uint32_t from, uint32_t to, int64_t count, bool stops) const {
  // The step at which the speed at `from` would reach the next count is
  // most often the event's or next to it: probed with its neighbour first,
  // it narrows what the bisection has left. Both keep the first step with
  // the event (the piece is monotone).
  const double per_step = run_x(from, 1) * dt_,
               edge = double(per_step > 0 ? count + 1 : count) / rad_to_count_;
  const double ahead = per_step != 0 ? (edge - run_x(from, 2)) / per_step : -1;
  if (ahead > 0 && ahead < double(to - from - 1)) {
    const uint32_t g = from + std::max<uint32_t>(1, uint32_t(std::ceil(ahead)));
    if (event_at(g, count, stops)) {
      to = g;
      if (to - from > 1) (event_at(g - 1, count, stops) ? to : from) = g - 1;
    } else {
      from = g;
      if (to - from > 1) (event_at(g + 1, count, stops) ? to : from) = g + 1;
    }
  }
  while (to - from > 1) {
    const uint32_t mid = from + (to - from) / 2;
    (event_at(mid, count, stops) ? to : from) = mid;
  }
  return to;
}

uint32_t AxisPlant::steps_before_breakaway(uint32_t lim) const {
  // The stuck current moves monotonically to V/R, the driving torque with
  // it: once past the breakaway torque, it stays past.
  const auto breaks = [&](uint32_t j) {
    return std::fabs(m_.kt_nm_per_a * run_stuck_current(j) - tau_load_) > m_.stiction_nm;
  };
  uint32_t from = k_, to = k_ + lim - 1;
  if (breaks(from)) return 0;
  if (!breaks(to)) return lim;
  while (to - from > 1) {
    const uint32_t mid = from + (to - from) / 2;
    (breaks(mid) ? to : from) = mid;
  }
  return to - k_;
}

void AxisPlant::set_friction(bool on) {
  friction_ = on;
  stuck_ = on && x_(1) == 0;
  anchored_ = false;
}

double AxisPlant::position_m() const {
  return x_(2) * rad_to_m_;
}

void AxisPlant::reset(double position_rad) {
  x_ = Eigen::Vector3d(0, 0, position_rad);
  steps_ = 0;
  stuck_ = friction_;
  anchored_ = false;
}

QuadPins quadrature_pins(int64_t count, int encoder_cpr) {
  const int64_t q = count & 3;  // count mod 4, negative counts included
  // The index at every whole turn (count mod cpr == 0, whatever the sign);
  // a power of two, as the virtual board's "no index" is, without a divide.
  const bool index =
      encoder_cpr > 0 &&
      ((encoder_cpr & (encoder_cpr - 1)) == 0 ? (count & (encoder_cpr - 1)) == 0 : count % encoder_cpr == 0);
  return QuadPins{q == 1 || q == 2, q >= 2, index};
}

int pwm_duty(const DriveConfig& d, int32_t u) {
  const int32_t s = saturate(u);
  return (s < 0 ? -s : s) >> (15 - d.pwm_bits);
}

double drive_volts(const DriveConfig& d, int32_t u) {
  const int32_t s = saturate(u);
  if (d.kind == DriveConfig::Kind::Pwm) {
    // A power of two's reciprocal is exact: the product is ldexp's, for
    // a fraction of its time (the drive changes every sample).
    const double v = double(pwm_duty(d, s)) * (1.0 / double(1u << d.pwm_bits)) * d.supply_v;
    return s < 0 ? -v : v;
  }
  const int32_t code = floor_shift(s, 16 - d.dac_bits);
  const double dac = code * std::ldexp(2 * d.dac_range_v, -d.dac_bits);
  return std::clamp(dac * d.amp_gain, -d.supply_v, d.supply_v);
}

double dac_volts(int bits, double range_v, double volts) {
  const double step = std::ldexp(2 * range_v, -bits);
  const double top = std::ldexp(1.0, bits - 1);
  const double code = std::clamp(std::nearbyint(volts / step), -top, top - 1);
  return code * step;
}

}  // namespace mc::sim
