#include "sim/vboard/virtual_board.hpp"

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <optional>
#include <stdexcept>

#include "host/base/errors.hpp"
#include "host/machine/workpiece.hpp"
#include "sim/plant/dc_motor.hpp"
#include "sim/plant/stepper_motor.hpp"
#include "sim/vboard/board_model.hpp"
#include "sim/vboard/contact.hpp"
#include "sim/vboard/uart_model.hpp"
#include "sim/vboard/wheel_socket.hpp"

namespace mc::sim {

namespace {

// The board top's parameters (rtl/motioncore_icebreaker.v defaults, as built).
constexpr long kBoardBaud = 1'000'000;

uint32_t whole_clocks_per_step(const MachineConfig& m) {
  const double k = m.clock_hz * m.plant_dt_s;
  if (!(k >= 2) || std::fabs(k - std::round(k)) > 1e-6)
    throw mc::host::InputError("plant_dt_s * clock_hz (" + m.source + ")", std::to_string(k),
                               "a whole number of at least 2 board clocks per plant step");
  return uint32_t(std::llround(k));
}

std::string sys_error(const char* call) {
  return std::string(call) + " failed: " + std::strerror(errno);
}

}  // namespace

const char* board_engine_name(BoardEngine e) {
  return e == BoardEngine::Rtl ? "rtl" : "twin";
}

BoardEngine parse_board_engine(const std::string& name, const std::string& what) {
  if (name == "twin") return BoardEngine::Twin;
  if (name == "rtl") return BoardEngine::Rtl;
  throw mc::host::InputError(what, "'" + name + "'", "twin or rtl");
}

struct VirtualBoard::Impl {
  using EncoderEdge = VirtualBoard::EncoderEdge;
  // One axis slot of the board: its plant, when configured: a DC servo on
  // the H-bridge pins, or a stepper whose driver counts the STEP pulses.
  struct Slot {
    std::unique_ptr<AxisPlant> plant;
    std::unique_ptr<StepperPlant> stepper;
    int cpr = 0;
    double supply_v = 0;
    double start_m = 0;                            // where the table stood at power-up (start_at)
    int64_t shown = 0, emit_from = 0, emit_n = 0;  // encoder edges of the current step
    int64_t steps = 0;                             // the stepper driver's STEP count
    bool step_pin = false;                         // STEP after the last clock
    bool present() const { return plant || stepper; }
    int64_t encoder_count() const { return plant ? plant->encoder_count() : stepper->position_steps(); }
    bool still() const { return plant ? plant->stuck() : stepper->speed_rad_s() == 0; }
    double position_m() const { return plant ? plant->position_m() : stepper ? stepper->position_m() : 0; }
    double table_m() const { return start_m + position_m(); }
    // A STEP edge in the clocks just run (the pins held through a stretch
    // of more than one: a stepping generator is never skipped over).
    void watch_step(bool step, bool dir) {
      if (step && !step_pin) steps += dir ? 1 : -1;
      step_pin = step;
    }
    void plant_step(int32_t drive, uint32_t clocks, bool enabled) {
      if (plant)
        plant->step(supply_v * double(drive) / double(clocks));
      else
        stepper->step(steps, enabled);
    }
  };

  Impl(const MachineConfig& cfg, uint32_t seed, BoardEngine e)
      : m(cfg),
        k(whole_clocks_per_step(cfg)),
        cpb(uart_clocks_per_bit(long(std::llround(cfg.clock_hz)), kBoardBaud)),
        engine(e),
        tx(cpb),
        rx(cpb) {
    if (m.axes.size() > size_t(kBoardAxes))
      throw mc::host::InputError("axes (" + m.source + ")", std::to_string(m.axes.size()),
                                 "at most " + std::to_string(kBoardAxes) + " (the board's x, y, z)");
    board = make_board_model(e, seed);
    for (size_t a = 0; a < m.axes.size(); ++a) {
      Slot& s = slot[a];
      if (m.axes[a].stepper)
        s.stepper = std::make_unique<StepperPlant>(m.axes[a], *m.axes[a].stepper, m.plant_dt_s);
      else
        s.plant = std::make_unique<AxisPlant>(m.axes[a], m.plant_dt_s);
      s.cpr = m.axes[a].encoder_cpr;
      s.supply_v = m.axes[a].drive.supply_v;
      m_per_count[a] = 1 / machine::counts_per_m(m.axes[a]);
      s.shown = s.encoder_count();
      ++naxes;
    }
    // Each contact bounces its own way, the same on every engine for a seed.
    const uint64_t seed_base = uint64_t(seed) << 8;
    for (int a = 0; a < naxes; ++a)
      if (const auto& h = m.axes[size_t(a)].home)
        lim[a] = Contact(bounce_steps(h->bounce_s), seed_base + uint64_t(a) + 1);
    has_probe = m.workpiece && naxes == kBoardAxes;
    if (has_probe) {
      probe = Contact(bounce_steps(m.probe.bounce_s), seed_base + kBoardAxes + 1);
      face.emplace(*m.workpiece);
    }
    place_contacts(true);
    for (int a = 0; a < kBoardAxes; ++a) {
      const Slot& s = slot[a];
      const QuadPins q = quadrature_pins(s.shown, s.present() ? s.cpr : 1 << 30);
      pins.enc_a[a] = q.a;
      pins.enc_b[a] = q.b;
    }
  }

  uint32_t bounce_steps(double s) const { return uint32_t(std::llround(s / m.plant_dt_s)); }
  bool has_home(int a) const { return a < naxes && m.axes[size_t(a)].home.has_value(); }

  // Whether each switch is truly closed where the tables are now.
  bool home_closed(int a) const {
    const machine::HomeConfig& h = *m.axes[size_t(a)].home;
    const double x = slot[a].table_m();
    return h.direction > 0 ? x >= h.switch_m : x <= h.switch_m;
  }
  bool probe_closed() const {
    look_at_face();
    return slot[2].table_m() * 1e3 <= face_z;
  }
  // The face under the probe (and its band, contacts_clear()), kept while
  // X and Y stand: the tables mostly stand, or move in Z alone.
  void look_at_face() const {
    const double x = slot[0].table_m() * 1e3, y = slot[1].table_m() * 1e3;
    if (x == face_x && y == face_y) return;
    face_x = x;
    face_y = y;
    face_z = face->z_mm(x, y);
    face_band = std::nan("");
  }
  // The switches where the tables are: at power-up (settle, no bounce) or
  // at a plant-step boundary.
  void place_contacts(bool settle) {
    const auto put = [settle](Contact& c, bool closed) { settle ? c.settle(closed) : c.step(closed); };
    for (int a = 0; a < naxes; ++a)
      if (has_home(a)) put(lim[a], home_closed(a));
    if (has_probe) put(probe, probe_closed());
    for (int a = 0; a < kBoardAxes; ++a) pins.lim[a] = has_home(a) && lim[a].pin();
    pins.probe = has_probe && probe.pin();
  }
  // No switch pin will change at the next boundary: none bouncing, none crossed.
  bool contacts_quiet() const {
    for (int a = 0; a < naxes; ++a)
      if (has_home(a) && (lim[a].bouncing() || lim[a].closed() != home_closed(a))) return false;
    return !has_probe || (!probe.bouncing() && probe.closed() == probe_closed());
  }

  // The spindle and coolant pins after edge `now` (a stepped clock: they
  // hold through skipped ones): a change is logged with SP_PWM's high
  // clocks over the edges since the change before, up to this one.
  void watch_spindle(uint64_t now) {
    const VirtualBoard::SpindleState st{board->sp_en(), board->sp_dir(), board->flood()};
    if (st == spindle) return;
    // The pins after this edge are the new state's: so is SP_PWM's level.
    const uint64_t high = board->sp_high_clocks() - board->sp_pwm();
    spindle_log.push_back({now, st, high - high_since, now - spindle_since});
    spindle = st;
    spindle_since = now;
    high_since = high;
  }

  // The handwheel: the clock at which the next edge is due (kNever: the
  // wheel rests), and showing every edge due by clock `now` on HW_A/HW_B.
  // Edge i of a turn of n comes at start + i * span / n.
  static constexpr uint64_t kNever = std::numeric_limits<uint64_t>::max();
  uint64_t next_wheel_edge() const {
    if (turns.empty()) return kNever;
    const Turn& t = turns.front();
    const uint64_t n = uint64_t(std::llabs(t.edges));
    return t.start + (t.done + 1) * t.span / n;
  }
  void show_wheel(uint64_t now) {
    if (next_wheel_edge() > now) return;  // the pins show the count already
    while (next_wheel_edge() <= now) {
      Turn& t = turns.front();
      wheel += t.edges < 0 ? -1 : 1;
      if (++t.done == uint64_t(std::llabs(t.edges))) turns.pop_front();
    }
    const QuadPins q = quadrature_pins(wheel, 1 << 30);  // no index on a handwheel
    pins.hw_a = q.a;
    pins.hw_b = q.b;
  }

  // Encoder edges of this step: the count the plant reached, at most one
  // edge every other clock (the decoder's rate), the rest carried over.
  void plan_edges() {
    for (int a = 0; a < naxes; ++a) {
      Slot& s = slot[a];
      const int64_t d = std::clamp<int64_t>(s.encoder_count() - s.shown, -int64_t(k / 2), int64_t(k / 2));
      s.emit_from = s.shown;
      s.emit_n = d;
      s.shown += d;
    }
  }

  // One plant step: the board's clocks in stretches with its input pins
  // held (an encoder edge every other clock while edges are due, RX at the
  // host line's bit edges), then the plants with the drive's mean over the
  // step.
  void plant_step(std::vector<uint8_t>& out) {
    place_contacts(false);
    plan_edges();
    uint32_t edges_until = 0;  // clocks in which some encoder pin still changes
    for (int a = 0; a < naxes; ++a)
      edges_until = std::max<uint32_t>(edges_until, uint32_t(2 * std::llabs(slot[a].emit_n)));
    bool active = !tx.idle() || rx.busy();
    int32_t drive[kBoardAxes] = {};
    uint32_t c = 0;
    while (c < k) {
      uint32_t hold = k - c;
      if (c < edges_until) {
        // Pins change only on even clocks while edges are due.
        if ((c & 1) == 0) {
          for (int a = 0; a < naxes; ++a) {
            const Slot& s = slot[a];
            if (s.emit_n == 0) continue;              // its pins show s.shown already
            const int64_t upto = int64_t(c / 2) + 1;  // edges shown by this clock
            const int64_t n = std::min<int64_t>(std::llabs(s.emit_n), upto);
            const int64_t to = s.emit_from + (s.emit_n < 0 ? -n : n);
            if (edge_log && n == upto) edge_log->push_back({cycles + c, a, to});
            const QuadPins q = quadrature_pins(to, s.cpr);
            pins.enc_a[a] = q.a;
            pins.enc_b[a] = q.b;
          }
        }
        const uint32_t next = (c | 1) + 1;  // the next even clock
        if (next < edges_until) hold = std::min(hold, next - c);
      }
      show_wheel(cycles + c);
      if (const uint64_t e = next_wheel_edge(); e - (cycles + c) < hold) hold = uint32_t(e - (cycles + c));
      pins.rx = tx.pin();
      const uint32_t steady = tx.steady();
      if (steady < hold) hold = steady + 1;
      const uint32_t n = board->run(pins, hold, drive, rx);
      for (int a = 0; a < naxes; ++a)
        if (slot[a].stepper) slot[a].watch_step(board->pwm(a), board->dir(a));
      tx.clock_n(n);
      c += n;
      watch_spindle(cycles + c);
    }
    active = active || !tx.idle() || rx.busy() || rx.has_byte();
    while (rx.has_byte()) out.push_back(rx.take());
    const bool enabled = board->drv_en();
    for (int a = 0; a < naxes; ++a) slot[a].plant_step(drive[a], k, enabled);
    cycles += k;
    if (active) last_activity = cycles;
  }

  // The twin's event loop: from a step boundary, the whole plant steps in
  // which the board only counts (no frame being parsed or answered, no PID
  // tick or done, no interpolator iteration, no encoder edge to show; a
  // frame the board sends goes out inside, so do the PID's drive updates,
  // and the data bits of a byte the host sends come in, the line being
  // known ahead) go by with the board advanced over them at once. The
  // plants take every step with the drive the clock-by-clock path would
  // count (the PWM pins follow their counters): by runs of equal drive
  // where no switch can change (hold_plants), else one by one. Positions,
  // bytes and the clocks of the encoder edges are the same
  // (VBoard.TwinAndRtlGiveIdenticalOutputs,
  // VBoard.HeldPlantRunsGiveTheStepsTheRtlTakes). Where the plants are held
  // by runs, the board takes the encoder edges they bring inside its
  // stretch, at the clocks plant_step() would show them (hold_plants);
  // otherwise the jump stops after the step in which an encoder count
  // changes or a switch is crossed. It never starts while a switch bounces
  // or an edge waits to be shown: the switch pins change only in
  // plant_step(). The spindle and coolant pins hold (SP_PWM aside,
  // whose high clocks the board model counts). A handwheel edge ends the
  // stretch at the step boundary before it: plant_step() shows it at its
  // clock.
  bool jump(uint64_t steps, std::vector<uint8_t>& out) {
    if (!contacts_quiet()) return false;
    if (const uint64_t e = next_wheel_edge(); e != kNever) steps = std::min(steps, (e - cycles) / k);
    if (steps == 0) return false;
    for (int a = 0; a < naxes; ++a)
      if (slot[a].encoder_count() != slot[a].shown) return false;
    pins.rx = tx.pin();
    // Host bytes on RX: the stretch runs through the bits of the one the
    // board is taking (the line is known ahead: tx.pin_after).
    const bool hosting = !tx.idle();
    const uint32_t limit = uint32_t(std::min<uint64_t>(steps * k, 1u << 30));
    uint64_t most =
        (hosting ? board->line_clocks(pins, limit, host_line) : board->idle_clocks(pins, limit)) / k;
    // The bytes the board sends go by inside; the receiver takes the first in
    // the jump's last step at the latest, as plant_step() would hand it on
    // then (the board's stretch may run past it: more than a step when a step
    // is that short, or a whole frame).
    if (const uint64_t t = clocks_to_byte(most * k); t != kNever) most = std::min(most, (t + k - 1) / k);
    if (most == 0) return false;
    uint64_t j = 0;
    if (contacts_clear()) {
      j = hold_plants(most);
      held_steps += j;
    } else {
      edges_.clear();  // the jump ends at the first edge
      shows_.clear();
      bool edge = false;
      const bool enabled = board->drv_en();
      while (j < most && !edge) {
        for (int a = 0; a < naxes; ++a) {
          Slot& s = slot[a];
          s.plant_step(s.plant ? board->idle_drive(a, uint32_t(j * k), k) : 0, k, enabled);
          edge = edge || s.encoder_count() != s.shown;
        }
        edge = edge || !contacts_quiet();
        ++j;
      }
    }
    const bool sending = rx.busy();
    if (hosting) {
      board->advance_line(pins, uint32_t(j * k), host_line, rx, edges_.data(), edges_.size());
      tx.clock_n(uint32_t(j * k));
    } else {
      board->advance(pins, uint32_t(j * k), rx, edges_.data(), edges_.size());
    }
    // The pins as the edges inside left them.
    for (const PinChange& e : edges_) {
      pins.enc_a[e.axis] = e.a;
      pins.enc_b[e.axis] = e.b;
    }
    for (const EncoderEdge& e : shows_) {
      slot[e.axis].shown = e.count;
      if (edge_log) edge_log->push_back({cycles + e.clock, e.axis, e.count});
    }
    cycles += j * k;
    if (hosting || sending || rx.busy() || rx.has_byte()) last_activity = cycles;
    while (rx.has_byte()) out.push_back(rx.take());
    return true;
  }

  // Of the next n clocks of the board's stretch, the clock in which the
  // receiver takes the first byte (or finds a framing error; counted from
  // 1), from a copy of it fed the stretch's TX; kNever: none.
  uint64_t clocks_to_byte(uint64_t n) const {
    UartBits copy = rx.bits();
    const auto none = [](uint8_t, bool) {};  // stops come at `at`, before the runs taken
    uint64_t t = 0, at = kNever;
    board->idle_tx(uint32_t(n), [&](bool level, uint32_t run) {
      while (run > 0 && at == kNever) {
        if (copy.busy()) {
          if (const uint64_t b = copy.clocks_to_byte(); b <= run) {
            at = t + b;
            return;
          }
          copy.clock_n(level, run, none);
          t += run;
          return;
        }
        if (level) {  // idle and the line high: nothing starts
          t += run;
          return;
        }
        copy.clock(level, none);  // a start bit
        ++t;
        --run;
      }
    });
    return at;
  }

  // No switch can change while every table stays within kFoldCounts of
  // the encoder count it shows now: each home switch more than that and
  // two counts away, the probe's gap wider than that many and two counts of
  // Z, and all the face can rise or fall within them of X and Y. (Servo
  // axes only: a stepper's table is not tied to a count.)
  static constexpr int64_t kFoldCounts = 32;
  bool contacts_clear() const {
    constexpr double reach = 2 + kFoldCounts;
    for (int a = 0; a < naxes; ++a) {
      if (!slot[a].plant) return false;
      if (has_home(a) &&
          std::fabs(slot[a].table_m() - m.axes[size_t(a)].home->switch_m) <= reach * m_per_count[a])
        return false;
    }
    if (!has_probe) return true;
    look_at_face();
    if (std::isnan(face_band))
      face_band =
          reach * 1e3 * m_per_count[2] +
          face->variation_mm(face_x, face_y, reach * 1e3 * m_per_count[0], reach * 1e3 * m_per_count[1]);
    return std::fabs(slot[2].table_m() * 1e3 - face_z) > face_band;
  }

  // The plants over up to `most` steps of a stretch, by runs of steps with
  // the same drive (AxisPlant::hold_counting): a switching drive's pin is
  // high through whole steps, then low through whole steps, with a step of
  // each edge between. Each count a plant reaches at the end of a step shows
  // on its pins from the next step's clock 0, as plant_step() shows one; the
  // board takes those edges inside its stretch where it can
  // (BoardModel::idle_foldable). The steps end after one that brings an
  // axis more than one count, or whose count the board cannot take there,
  // or that takes a table past kFoldCounts from where it stood (then
  // plant_step() shows it). contacts_clear() must hold. Returns the steps
  // taken; edges_ has the edges inside them.
  uint64_t hold_plants(uint64_t most) {
    uint64_t end = most;
    uint64_t took[kBoardAxes] = {};
    int64_t count0[kBoardAxes] = {};
    for (int a = 0; a < naxes; ++a) {
      Slot& s = slot[a];
      count0[a] = s.shown;
      if (!ahead[a]) ahead[a] = std::make_unique<AxisPlant>(*s.plant);
      ahead[a]->take_motion(*s.plant);  // to take the steps again, if fewer
      counts[a].clear();
      took[a] = hold_axis(a, end, counts[a]);
      end = std::min(end, took[a]);
    }
    // The edges inside: each a count reached at the end of step c.step,
    // shown from clock c.step * k.
    shows_.clear();
    for (int a = 0; a < naxes; ++a)
      for (const AxisPlant::CountChange& c : counts[a]) {
        if (c.step >= end) break;
        if (std::llabs(c.count - count0[a]) > kFoldCounts) {
          end = c.step;
          break;
        }
        shows_.push_back({c.step * k, a, c.count});
      }
    std::stable_sort(shows_.begin(), shows_.end(),
                     [](const EncoderEdge& x, const EncoderEdge& y) { return x.clock < y.clock; });
    while (!shows_.empty() && shows_.back().clock >= end * k) shows_.pop_back();
    edges_.clear();
    for (const EncoderEdge& e : shows_) {
      const QuadPins q = quadrature_pins(e.count, slot[e.axis].cpr);
      edges_.push_back(PinChange{uint32_t(e.clock), e.axis, q.a, q.b, false});
    }
    if (const size_t f = board->idle_foldable(edges_.data(), edges_.size()); f < edges_.size()) {
      end = edges_[f].clock / k;
      edges_.resize(f);
      shows_.resize(f);
    }
    // An axis that went past the end takes its steps again, up to it.
    for (int a = 0; a < naxes; ++a)
      if (took[a] > end) {
        slot[a].plant->take_motion(*ahead[a]);
        counts[a].clear();
        if (hold_axis(a, end, counts[a]) != end)
          throw std::logic_error("virtual board: a plant held again took other steps");
      }
    return end;
  }
  // Axis a's plant over up to end steps, through its count changes (into
  // changes, steps counted from 1): each step with the drive's mean over
  // it, runs of whole steps through which the bridge holds one level (on or
  // off: the PWM counter's phase and the duty tell how many) at once. Stops
  // after a step that moves the count by more than one.
  uint64_t hold_axis(int a, uint64_t end, std::vector<AxisPlant::CountChange>& changes) {
    Slot& s = slot[a];
    uint64_t j = 0;
    AxisPlant::Samples none;
    while (j < end) {
      const int32_t d = board->idle_drive(a, uint32_t(j * k), k);
      const uint64_t r =
          std::max<uint32_t>(1, board->idle_drive_runs(a, uint32_t(j * k), k, uint32_t(end - j)));
      const AxisPlant::Held h =
          s.plant->hold_counting(s.supply_v * double(d) / double(k), r, none, changes, j);
      j += h.steps;
      if (h.big) break;
    }
    return j;
  }

  MachineConfig m;
  uint32_t k;
  int cpb;
  BoardEngine engine;
  std::unique_ptr<BoardModel> board;
  IcebreakerPins pins;
  Slot slot[kBoardAxes];
  double m_per_count[kBoardAxes] = {};  // table travel per encoder count
  int naxes = 0;
  UartSender tx;
  UartReceiver rx;
  // The host's line ahead of time, for the board's stretches through a byte.
  const BoardModel::RxLine host_line = [this](uint64_t t) { return tx.pin_after(t); };
  uint64_t cycles = 0, last_activity = 0;
  uint64_t held_steps = 0;  // held_steps()
  // hold_plants(): each plant as it was (to take the steps again), the
  // counts each reached.
  std::unique_ptr<AxisPlant> ahead[kBoardAxes];
  std::vector<AxisPlant::CountChange> counts[kBoardAxes];
  // hold_plants(): the edges the board takes inside the jump (clocks from
  // its start), as pins and as the counts they show.
  std::vector<PinChange> edges_;
  std::vector<EncoderEdge> shows_;
  std::vector<EncoderEdge>* edge_log = nullptr;  // log_encoder_edges()
  // The switches: each home switch on its axis's limit pin, the probe.
  Contact lim[kBoardAxes], probe;
  bool has_probe = false;
  // The face (surface_z_mm) at the last X, Y asked, and the band
  // contacts_clear() wants there (NaN: not asked yet): a cache, so mutable.
  mutable std::optional<machine::SurfaceCache> face;
  mutable double face_x = std::nan(""), face_y = std::nan(""), face_z = 0, face_band = 0;
  // The spindle and coolant: the pins now, their changes, and where the
  // interval since the last change began (clock, SP_PWM high clocks).
  VirtualBoard::SpindleState spindle;
  std::vector<VirtualBoard::SpindleEvent> spindle_log;
  uint64_t spindle_since = 0, high_since = 0;
  // The handwheel: the turns still to come (the one in hand first; edges
  // signed, done counts the edges shown), the count the pins show, and the
  // clock the last turn ends.
  struct Turn {
    uint64_t start = 0, span = 0;
    int64_t edges = 0;
    uint64_t done = 0;
  };
  std::deque<Turn> turns;
  int64_t wheel = 0;
  uint64_t wheel_free = 0;
};

VirtualBoard::VirtualBoard(const MachineConfig& m, uint32_t seed, BoardEngine e)
    : impl_(std::make_unique<Impl>(m, seed, e)) {}
VirtualBoard::~VirtualBoard() = default;

void VirtualBoard::send(const uint8_t* p, size_t n) {
  // A host opens the port of a board that is up: its first byte reaches RX
  // after the power-on reset. (At clock 0 the reset would swallow the start
  // of the first frame, and the host would wait out its first timeout,
  // 200 ms of board time, before trying again.)
  if (impl_->cycles < kPowerOnClocks) {
    std::vector<uint8_t> none;  // the board sends nothing in its reset
    run(kPowerOnClocks - impl_->cycles, none, false);
  }
  for (size_t i = 0; i < n; ++i) impl_->tx.send(p[i]);
}
size_t VirtualBoard::rx_backlog() const {
  return impl_->tx.queued();
}
void VirtualBoard::run(uint64_t clocks, std::vector<uint8_t>& out, bool until_output) {
  const uint64_t end = impl_->cycles + clocks;
  const size_t before = out.size();
  while (impl_->cycles < end && !(until_output && out.size() > before)) {
    const uint64_t steps = (end - impl_->cycles + impl_->k - 1) / impl_->k;
    if (!impl_->jump(steps, out)) impl_->plant_step(out);
  }
}
uint64_t VirtualBoard::cycles() const {
  return impl_->cycles;
}
uint64_t VirtualBoard::stepped_clocks() const {
  return impl_->board->stepped();
}
uint64_t VirtualBoard::held_steps() const {
  return impl_->held_steps;
}
BoardEngine VirtualBoard::engine() const {
  return impl_->engine;
}
double VirtualBoard::clock_hz() const {
  return impl_->m.clock_hz;
}
uint32_t VirtualBoard::clocks_per_step() const {
  return impl_->k;
}
uint64_t VirtualBoard::link_quiet_clocks() const {
  return impl_->cycles - impl_->last_activity;
}
bool VirtualBoard::dormant() const {
  if (link_quiet_clocks() <= kMaxWatchdogClocks || !impl_->contacts_quiet()) return false;
  for (int a = 0; a < kBoardAxes; ++a) {
    const auto& s = impl_->slot[a];
    if (impl_->board->drv_en() || (s.present() && !s.still())) return false;
  }
  return impl_->turns.empty();  // the board counts every handwheel edge, drives on or off
}
double VirtualBoard::position_m(int axis) const {
  return impl_->slot[axis].table_m();
}
void VirtualBoard::start_at(int axis, double table_m) {
  if (impl_->cycles != 0) throw std::logic_error("VirtualBoard::start_at: the board has run already");
  if (axis < 0 || axis >= impl_->naxes)
    throw std::logic_error("VirtualBoard::start_at: axis " + std::to_string(axis) + " is not configured");
  impl_->slot[axis].start_m = table_m;
  impl_->place_contacts(true);
}
bool VirtualBoard::limit_pin(int axis) const {
  return impl_->pins.lim[axis];
}
bool VirtualBoard::probe_pin() const {
  return impl_->pins.probe;
}
uint64_t VirtualBoard::limit_edges(int axis) const {
  return impl_->lim[axis].edges();
}
uint64_t VirtualBoard::probe_edges() const {
  return impl_->probe.edges();
}
VirtualBoard::SpindleState VirtualBoard::spindle_state() const {
  return impl_->spindle;
}
const std::vector<VirtualBoard::SpindleEvent>& VirtualBoard::spindle_log() const {
  return impl_->spindle_log;
}
uint64_t VirtualBoard::spindle_high_clocks() const {
  return impl_->board->sp_high_clocks();
}
bool VirtualBoard::drive_enabled(int /*axis*/) const {
  return impl_->board->drv_en();  // one DRV_EN pin for every driver
}
int64_t VirtualBoard::driver_steps(int axis) const {
  return impl_->slot[axis].steps;
}
int64_t VirtualBoard::lost_full_steps(int axis) const {
  const auto& s = impl_->slot[axis];
  return s.stepper ? s.stepper->lost_full_steps(s.steps) : 0;
}
int VirtualBoard::configured_axes() const {
  return impl_->naxes;
}
void VirtualBoard::turn_handwheel(int detents, double seconds) {
  if (!(seconds >= 0 && seconds <= 3600))
    throw mc::host::InputError("handwheel turn", mc::host::format_number(seconds) + " s", "0 to 3600 s");
  // A thousand turns of the wheel at most: edge times stay far inside 64 bits.
  if (std::abs(detents) > kMaxHandwheelDetents)
    throw mc::host::InputError("handwheel turn", std::to_string(detents) + " detents",
                               "at most " + std::to_string(kMaxHandwheelDetents) + " either way");
  if (detents == 0) return;
  Impl& b = *impl_;
  const int64_t edges = int64_t(detents) * kHandwheelCountsPerDetent;
  const uint64_t n = uint64_t(std::llabs(edges));
  Impl::Turn t;
  t.start = std::max(b.cycles, b.wheel_free);
  t.span = std::max(uint64_t(std::llround(seconds * b.m.clock_hz)), n * kHandwheelEdgeClocks);
  t.edges = edges;
  b.turns.push_back(t);
  b.wheel_free = t.start + t.span;
}
int64_t VirtualBoard::handwheel_count() const {
  return impl_->wheel;
}
double VirtualBoard::handwheel_done_s() const {
  return double(impl_->wheel_free) / clock_hz();
}
void VirtualBoard::tap_segments(std::vector<uint32_t>* words) {
  impl_->board->tap_segments(words);
}
void VirtualBoard::log_encoder_edges(std::vector<EncoderEdge>* log) {
  impl_->edge_log = log;
}

// ---------------------------------------------------------------------------

Pty::Pty() {
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (master_ < 0) throw std::runtime_error(sys_error("posix_openpt"));
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
    const std::string e = sys_error("grantpt/unlockpt");
    ::close(master_);
    throw std::runtime_error(e);
  }
  const char* name = ::ptsname(master_);
  if (!name) {
    const std::string e = sys_error("ptsname");
    ::close(master_);
    throw std::runtime_error(e);
  }
  path_ = name;
  slave_ = ::open(name, O_RDWR | O_NOCTTY);
  if (slave_ < 0) {
    const std::string e = sys_error(("open " + path_).c_str());
    ::close(master_);
    throw std::runtime_error(e);
  }
  // Raw bytes both ways: no echo, no line editing, no CR/LF mapping.
  termios tio{};
  ::tcgetattr(slave_, &tio);
  ::cfmakeraw(&tio);
  ::tcsetattr(slave_, TCSANOW, &tio);
}

Pty::~Pty() {
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
}

ServeStatus serve(VirtualBoard& board, Pty& pty, const ServeOptions& opt, const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  // The board runs in slices of 100 us: the host's bytes reach the RX line at
  // most that late, well inside the protocol's 1 ms byte timeout.
  const uint64_t slice = std::max<uint64_t>(1, uint64_t(std::llround(100e-6 * board.clock_hz())));
  const double period_s = double(slice) / board.clock_hz();
  // Paced, the board runs ahead of the wall clock by up to kLead; by up to
  // kLeadHost for a millisecond of board time after host bytes were on its
  // line, so that a frame the host writes in pieces reaches the board with
  // gaps within half a millisecond of the host's own, as its byte timeout
  // (1 ms) expects.
  constexpr double kLead = 4e-3, kLeadHost = 1e-3;
  const int fd = pty.master_fd();
  const auto t0 = Clock::now();
  auto last_host = t0;
  double paused_s = 0;  // wall time spent dormant: the board's clock stood still
  ServeStatus st;
  double last_report_wall = 0, last_report_board = board.board_seconds();
  std::vector<uint8_t> out;
  uint8_t buf[512];
  // Free-running: host bytes came and the board has answered them since.
  bool asked = false, answered = false;
  const uint64_t quiet_line = 2 * uint64_t(std::llround(board.clock_hz() / 1e5));  // two bytes' time
  // TX bytes not written yet wait at most this long (board time), or until
  // a packet's payload has gathered (out_since: when the first came).
  constexpr size_t kPacket = 62;
  const uint64_t latency = uint64_t(std::llround(1e-3 * board.clock_hz()));
  uint64_t out_since = 0;
  uint64_t host_at = 0;  // the board clock at which host bytes were last on RX
  const auto flush = [&] {
    if (out.empty()) return;
    const ssize_t n = ::write(fd, out.data(), out.size());
    const size_t sent = n > 0 ? size_t(n) : 0;
    st.bytes_out += sent;
    st.bytes_dropped += out.size() - sent;
    answered = answered || (asked && sent > 0);
    out.clear();
  };

  const auto report = [&](bool force) {
    st.wall_s = seconds_since(t0);
    st.board_s = board.board_seconds();
    st.run_wall_s = st.wall_s - paused_s;
    const double dw = st.wall_s - last_report_wall;
    if (!force && dw < opt.status_every_s) return;
    if (dw > 0) st.rt_factor = (st.board_s - last_report_board) / dw;
    last_report_wall = st.wall_s;
    last_report_board = st.board_s;
    if (opt.status) opt.status(st);
  };
  const auto take_input = [&] {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) return false;
    board.send(buf, size_t(n));
    st.bytes_in += uint64_t(n);
    host_at = board.cycles();  // a short request may be on the line for less than a slice
    last_host = Clock::now();
    asked = true;
    answered = false;
    return true;
  };

  // The pseudo-terminal and the wheel socket: either wakes a sleep.
  pollfd fds[2] = {{fd, POLLIN, 0}, {opt.wheel ? opt.wheel->fd() : -1, POLLIN, 0}};
  const auto wheel_asks = [&] {
    if (!opt.wheel || !opt.wheel->serve(board)) return;
    last_host = Clock::now();
  };

  while (!stop.load()) {
    if (board.rx_backlog() < 64) take_input();
    wheel_asks();
    const size_t had = out.size();
    board.run(slice, out);
    if (had == 0 && !out.empty()) out_since = board.cycles();
    if (board.rx_backlog() > 0) host_at = board.cycles();
    // The board's USB bridge (the FT2232H) ships TX bytes in packets: when a
    // packet's worth has gathered or its latency timer runs out. An answer
    // goes as soon as the line falls quiet after it. Each write to the
    // terminal costs the kernel more than the board's 100 us of bytes.
    if (out.size() >= kPacket || board.cycles() - out_since >= latency ||
        board.link_quiet_clocks() >= quiet_line)
      flush();
    if (!opt.paced && opt.host_wait_s > 0 && answered && board.link_quiet_clocks() >= quiet_line) {
      // The board answered and the line went quiet: the host's next request
      // comes after its own reaction time, which is wall time. Running on
      // meanwhile would turn a millisecond of it into tens of milliseconds of
      // board time; wait for it a little instead (the host then sees the
      // board's time pass as a real board's would).
      asked = answered = false;
      const auto since = Clock::now();
      pollfd p{fd, POLLIN, 0};
      ::poll(&p, 1, int(std::lround(opt.host_wait_s * 1e3)));
      st.host_wait_s += seconds_since(since);
    }
    ++st.periods;
    if (opt.paced) {
      const double ahead = board.board_seconds() - (seconds_since(t0) - paused_s);
      st.model_bound = ahead < 0;
      if (ahead < -period_s) ++st.late_periods;
      // The board may run up to kLead ahead of the wall clock, and sleeps
      // back to half of it (every 2 ms rather than every period): a late
      // wake-up, a few milliseconds in which the OS runs something else or
      // a burst of work for the model (the host filling the segment queue)
      // eats into the lead instead of making periods late. A host byte
      // ends the sleep; the bytes for the host go before it.
      const double lead = board.cycles() - host_at < latency ? kLeadHost : kLead;
      if (ahead > lead) {
        flush();
        const double wait = ahead - lead / 2;
        const timespec ts{time_t(wait), long((wait - std::floor(wait)) * 1e9)};
        ::ppoll(fds, 2, &ts, nullptr);
      }
    } else {
      st.model_bound = true;
    }
    // A client waiting for its turn's answer gets it first (the next round).
    if (board.dormant() && board.rx_backlog() == 0 && !(opt.wheel && opt.wheel->waiting())) {
      st.dormant = true;
      report(true);
      const auto since = Clock::now();
      while (!stop.load()) {
        if (::poll(fds, 2, 200) > 0 && (take_input() || fds[1].revents)) break;
        if (opt.idle_exit_s > 0 && seconds_since(last_host) > opt.idle_exit_s) break;
      }
      paused_s += seconds_since(since);
      st.dormant = false;
      last_report_wall = seconds_since(t0);
      last_report_board = board.board_seconds();
    }
    if (opt.idle_exit_s > 0 && seconds_since(last_host) > opt.idle_exit_s) break;
    report(false);
  }
  flush();
  st.wall_s = seconds_since(t0);
  st.board_s = board.board_seconds();
  st.run_wall_s = st.wall_s - paused_s;
  return st;
}

std::string describe_speed(const ServeStatus& s, bool paced) {
  char line[256];
  if (paced)
    std::snprintf(line, sizeof line, "%llu periods of 100 us, %llu late (%.3f %%), %.3f x real time",
                  static_cast<unsigned long long>(s.periods), static_cast<unsigned long long>(s.late_periods),
                  s.periods ? 100.0 * double(s.late_periods) / double(s.periods) : 0.0, s.speed());
  else
    std::snprintf(line, sizeof line,
                  "free-running: %.3f s of board time in %.3f s (%.2f x real time; %.3f s of it waiting for "
                  "the host's next request)",
                  s.board_s, s.run_wall_s, s.speed(), s.host_wait_s);
  return line;
}

}  // namespace mc::sim
