// motion_core twin: the motion datapath clock by clock. Mirrors
// rtl/motion_core.v, which documents how to drive it: the decoders give the
// feedback, the interpolator the command, pid_core closes the loops, and the
// drive stage turns each sample's output into PWM and direction.
//
// outputs() describes the current clock (before its edge); clock(in) is the
// edge. The sub-blocks are the twins of the RTL's instances, composed in the
// same way, so every output equals the RTL's bit for bit.
#pragma once

#include <algorithm>
#include <climits>
#include <cstdint>

#include "interp_core.hpp"
#include "pid_core.hpp"
#include "quad_decoder.hpp"

namespace mc {

template <int NAXES>
struct MotionIn {
  bool rst = false;
  // PID configuration port
  bool pid_we = false;
  uint8_t pid_waddr = 0;
  uint32_t pid_wdata = 0;
  bool pid_re = false;
  uint8_t pid_raddr = 0;
  // interpolator
  bool seg_wr = false;
  uint32_t seg_wdata = 0;
  bool ip_abort = false, ip_hold = false, ip_clr = false;
  uint8_t ip_set = 0;  // a strobe per axis
  int32_t ip_set_pos[3] = {};
  uint8_t ip_jog = 0;  // a strobe per axis: one count while idle (the handwheel)
  bool ip_jog_neg = false;
  // encoders
  bool enc_a[NAXES] = {}, enc_b[NAXES] = {}, enc_z[NAXES] = {};
  bool enc_latch[NAXES] = {};  // synchronous latch strobes (home switch, probe)
  uint32_t enc_filt[NAXES] = {};
  bool enc_dir_inv[NAXES] = {}, enc_idx_clr_en[NAXES] = {};
  bool enc_idx_arm[NAXES] = {}, enc_idx_disarm[NAXES] = {}, enc_err_clr[NAXES] = {};
  // drive control
  bool drv_allow[NAXES] = {};
  bool drv_ovr[NAXES] = {};     // level: the host drives the axis
  bool drv_ovr_we[NAXES] = {};  // strobe: that axis's drv_cmd <- drv_ovr_val
  int16_t drv_ovr_val = 0;
  // sample RAM read: axis << 3 | field
  uint8_t smp_raddr = 0;

  bool operator==(const MotionIn&) const = default;
};

template <int NAXES>
struct MotionOut {
  bool operator==(const MotionOut&) const = default;
  bool pid_wready = false, pid_rready = false, pid_rvalid = false;
  uint32_t pid_rdata = 0;
  int seg_count = 0;
  bool ip_busy = false, ip_underrun = false, ip_ovf = false;
  int ip_seg_cnt = 0;
  QuadOut enc[NAXES];
  bool pwm[NAXES] = {}, dir[NAXES] = {}, drv_en[NAXES] = {};
  int16_t drv_u[NAXES] = {};
  bool tick = false, done = false;
  uint32_t smp_rdata = 0;
  int16_t drv_cmd[NAXES] = {};
  bool smp_sat[NAXES] = {}, pid_en[NAXES] = {};
  int32_t pos[NAXES] = {}, cmd[NAXES] = {};
};

// Fields of the sample RAM (rtl/motion_core.v): smp_raddr = axis << 3 | field.
// OUT is {[17] PID enabled, [16] saturated, [15:0] u}; FOLLOW is command -
// feedback saturated to 32 bits (the error before deadband and clamp).
enum SampleField : uint8_t { SMP_CMD = 0, SMP_FB = 1, SMP_ERR = 2, SMP_OUT = 3, SMP_FOLLOW = 4 };
constexpr int SMP_FIELDS = 8;  // per axis: the address has three field bits

// An encoder's pins changing inside a stretch: from its clock-th clock on
// (counted from the stretch's first, 0), axis `axis` shows a, b, z.
struct PinChange {
  uint32_t clock;
  int axis;
  bool a, b, z;
};

// IDX_RAM: the decoders' index latches in block RAM (rtl/quad_decoder.v), as
// the board builds them.
template <int NAXES, int FIFO_AW = 9, int PWM_BITS = 9, int FILT_W = 8, bool IDX_RAM = false,
          bool SERVO = true>
class MotionCore {
  static_assert(NAXES >= 1 && NAXES <= 3, "motion_core: NAXES must be 1..3");
  static_assert(PWM_BITS >= 1 && PWM_BITS <= 15, "motion_core: PWM_BITS must be 1..15");

 public:
  bool operator==(const MotionCore&) const = default;
  using In = MotionIn<NAXES>;
  using Out = MotionOut<NAXES>;
  using Pid = PidCoreClocked<NAXES, SERVO>;
  using Decoder = QuadDecoder<FILT_W, 8, 32, 16, IDX_RAM, false>;  // errors to 255, no load
  static constexpr int latency = Pid::latency;
  // The sweep clock (Pid::sweep_clock) in which pid_core streams axis a's
  // output word, which the drive takes at that clock's edge: slot a + 1,
  // cycle 10 of rtl/pid_core.v's schedule, 18 cycles a slot.
  static constexpr int drv_clock(int a) { return 1 + 18 * (a + 1) + 10; }
  static_assert(drv_clock(NAXES - 1) < latency, "the last drive update precedes done");
  static constexpr int pwm_bits = PWM_BITS;

  // PWM duty, in counter steps of 2^PWM_BITS, of a drive value.
  static constexpr uint32_t duty(int16_t u) {
    return (u < 0 ? uint32_t(-int32_t(u)) : uint32_t(u)) >> (15 - PWM_BITS);
  }

  // The current clock's outputs. The PID's read port needs this clock's write
  // request (a read is refused while a write is presented).
  Out outputs(bool pid_we = false) const {
    Out o;
    o.pid_wready = pid_.wready();
    o.pid_rready = pid_.rready(pid_we);
    o.pid_rvalid = pid_.rvalid();
    o.pid_rdata = pid_.rdata();
    o.seg_count = ip_.count();
    o.ip_busy = ip_.busy();
    o.ip_underrun = ip_.underrun();
    o.ip_ovf = ip_.ovf();
    o.ip_seg_cnt = ip_.seg_cnt();
    o.tick = pid_.tick();
    o.done = pid_.done();
    o.smp_rdata = r_.smp_rdata;
    for (int a = 0; a < NAXES; ++a) {
      o.enc[a] = dec_[a].out();
      o.pwm[a] = r_.pwm[a];
      o.dir[a] = r_.dir[a];
      o.drv_en[a] = r_.drv_en[a];
      o.drv_u[a] = r_.drv_u[a];
      o.drv_cmd[a] = r_.drv_cmd[a];
      o.smp_sat[a] = r_.smp_sat[a];
      o.pid_en[a] = pid_.enabled(a);
      o.pos[a] = o.enc[a].pos;
      o.cmd[a] = ip_.pos(a);
    }
    return o;
  }

  void clock(const In& in) {
    // Nonblocking: every right-hand side reads r, this clock's registers;
    // the next values go straight into r_ (n).
    const Regs r = r_;
    Regs& n = r_;
    int32_t cmd[NAXES], fb[NAXES];
    for (int a = 0; a < NAXES; ++a) {
      cmd[a] = ip_.pos(a);
      fb[a] = dec_[a].out().pos;
    }
    const bool tick = pid_.tick(), done = pid_.done();

    if (tick)
      for (int a = 0; a < NAXES; ++a) {
        n.in_cmd[a] = cmd[a];
        n.in_fb[a] = fb[a];
      }
    // Sample RAM (publish()): a reset neither swaps nor clears it.
    n.smp_rdata = read_bank(in.smp_raddr);
    if (!in.rst && done) publish(r);
    for (int a = 0; a < NAXES; ++a) {
      if (in.rst) {
        n.drv_cmd[a] = 0;
        n.smp_sat[a] = false;
        continue;
      }
      if (in.drv_ovr_we[a])
        n.drv_cmd[a] = in.drv_ovr_val;
      else if (pid_.sweep_clock() == drv_clock(a) && !in.drv_ovr[a])
        n.drv_cmd[a] = int16_t(pid_.core().u(a));
    }

    // Drive stage.
    n.pcnt = in.rst ? 0 : (r.pcnt + 1) & pwm_mask;
    for (int a = 0; a < NAXES; ++a) {
      const int16_t u = u_sel(r, in, a);
      if (in.rst) {
        n.drv_u[a] = 0;
        n.pwm[a] = n.dir[a] = n.drv_en[a] = false;
      } else {
        n.drv_u[a] = u;
        n.pwm[a] = duty(u) > r.pcnt;
        n.dir[a] = u < 0;
        n.drv_en[a] = drv_en(in, a);
      }
    }

    // Sub-blocks, each on the values of this clock.
    pid_.clock(pid_in(in, cmd, fb));

    const InterpIn ii = interp_in(in);
    // An idle interpolator stands still after two quiet clocks
    // (InterpCore::quiet); from then on its clock is skipped.
    if (in.rst) {
      ip_.reset();
      ip_still_ = 0;
    } else if (!ip_.quiet(ii)) {
      if (ip_.state() == InterpCore<FIFO_AW>::ST_RUN && ii == InterpIn{})
        ip_.clock_running();
      else
        ip_.clock(ii);
      ip_still_ = 0;
    } else if (ip_still_ < 2) {
      ip_.clock(ii);
      ++ip_still_;
    }

    // A settled decoder only ages its last edge, and at a tick publishes
    // its velocity and age: skip(1) and skip_sampled() are those clocks,
    // for much less work than step() (the clocks with pin activity step).
    for (int a = 0; a < NAXES; ++a) {
      const QuadIn qi = quad_in(in, a, tick);
      if (!dec_[a].quiet_but_sample(qi))
        dec_[a].step(qi);
      else if (tick)
        dec_[a].skip_sampled();
      else
        dec_[a].skip(1);
    }
  }

  // Fast-forward for long simulations: true when n clocks with these inputs
  // would change nothing but counters (no tick, drive update or done due,
  // decoders settled, interpolator idle, drive value unchanged); skip(n)
  // then does them at once (the inputs held are those quiet() was given).
  // The PWM pin ends as the last of those clocks leaves it.
  bool quiet(const In& in, uint32_t n) const { return quiet_as(in, n, Let{}); }
  // What quiet_as() may also let change in the n clocks, which the core's
  // readers see only at its next tick or, for the drive, from the clocks
  // drive_in() tells (quiet_limit_as() bounds n to the tick and done):
  struct Let {
    // The sample RAM's read port, whose address the board's register file
    // walks after a sample (McBoard::walk_clocks; read_port(raddr) is the
    // port's clock).
    bool port = false;
    // A running segment: its position moves, which the PID reads at a tick.
    bool busy = false;
    // Decoders working through an edge: with their pins held, each steps
    // until it settles, its count moving (read by the PID at a tick) and
    // nothing a reader sees between ticks (QuadDecoder::settle_clocks). The
    // skip needs the inputs quiet_as() was given.
    bool settle = false;
    // The sweep's drive updates: each axis's drive command takes the
    // sample's output at its clock (drv_clock), the drive value and pins
    // follow a clock and two later; drive_in() gives the pins over the
    // stretch, drive_change() where they change. Done and the tick stay
    // out (quiet_limit_as).
    bool drive = false;
    // The PID's samples: a stretch may end with the edge that raises the
    // tick or done (quiet_limit_as() one clock longer), and the sample
    // port follows its address (as read_port() would leave it). The tick
    // and done themselves are the caller's to clock() (quiet_but_pid()),
    // so that a stretch may go through a sample, drive_steps() telling the
    // drive up to the next sweep's first update.
    bool sample = false;
    // With sample: a stretch may also go through done (the sample's words
    // into the sample RAM, its bank published, the saturation flags), the
    // tick alone ending it; done_in() before the skip tells done's clock.
    bool done = false;
    // With sample and done: a stretch may also go through the tick, which
    // skip_busy_as() clocks inside it (with the pins as the changes have
    // them by then; the tick's clock may move the position, and may be
    // the last), up to the new sweep's first drive command. The sweep
    // reads the counts and the command of the tick's clock.
    bool tick = false;
  };
  // Of the clocks from this one, the number of the sweep's done (0: this
  // one), or Pid::kNoDone.
  uint32_t done_in() const { return pid_.done_in(); }
  bool quiet_as(const In& in, uint32_t n, Let let) const {
    return quiet_but_interp(in, n, let) && interp_quiet(in, n, let.busy);
  }
  // This clock is quiet_as(in, 1, let) but for being the PID's tick or done
  // (or the sample port's): clock() it.
  bool quiet_but_pid(const In& in, Let let) const {
    return quiet_but_interp(in, 1, let, true) && interp_quiet(in, 1, let.busy);
  }
  // quiet_as(in, n, let) (false for n = 0), and where it is not,
  // quiet_but_pid(in, let), for the checks of one: kQuiet, kPidClock or 0.
  // *others_out (unless null): whether the checks but the PID's held.
  static constexpr int kQuiet = 2, kPidClock = 1;
  int quiet_or_pid(const In& in, uint32_t n, Let let, bool* others_out = nullptr) const {
    const typename Pid::In pi = pid_in(in, nullptr, nullptr);
    const bool others = quiet_but_pid_interp(in, n, let) && interp_quiet(in, n, let.busy);
    if (others_out) *others_out = n > 0 && let.drive && let.busy && others;
    if (others && pid_quiet(pi, n, let)) return kQuiet;
    // Only the sweep's drive updates (unless let.drive) and a running
    // interpolator's next iteration (unless let.busy) depend on n.
    const bool one = n > 0 && let.drive && let.busy
                         ? others
                         : quiet_but_pid_interp(in, 1, let) && interp_quiet(in, 1, let.busy);
    return one && pid_.quiet_but_timers(pi) ? kPidClock : 0;
  }
  // quiet_or_pid(in, n, let) where it last told *others_out with these
  // inputs, and only skip_busy_as(in, .., let) and clock(in) of what it
  // allowed came since: none of those changes the other checks' answer
  // (decoders stay quiet, or settle on along the same path, a sample
  // strobe or not; the interpolator stays idle, or running short of its
  // end; the drive enables are what the inputs make them). Only the PID's
  // are asked.
  int quiet_or_pid_again(const In& in, uint32_t n, Let let) const {
    const typename Pid::In pi = pid_in(in, nullptr, nullptr);
    if (n > 0 && pid_quiet(pi, n, let)) return kQuiet;
    return pid_.quiet_but_timers(pi) ? kPidClock : 0;
  }
  // n clocks after quiet_as(in, n, let); with let.busy, n must not reach
  // the clock that ends the running segment (InterpCore::run_to_end on a
  // copy tells how far that is).
  // The pins may change as the first `count` of ch say (foldable(); these
  // n clocks are the stretch's from-th on, as skip_others() counts).
  void skip_as(const In& in, uint32_t n, Let let, const PinChange* ch = nullptr, size_t count = 0,
               uint32_t from = 0) {
    if (let.busy && ip_.state() == InterpCore<FIFO_AW>::ST_RUN)
      ip_.run_to_end(n);
    else
      skip_interp(n);
    skip_others(n, &in, let, ch, count, from);
  }
  void read_port(uint8_t raddr) { r_.smp_rdata = read_bank(raddr); }
  uint32_t port_word(uint8_t raddr) const { return read_bank(raddr); }
  // Like quiet(), but the interpolator may run a segment meanwhile, with no
  // input (its position moving: the PID reads it only at a tick).
  // skip_busy(in, n) then does at most n such clocks, stopping before the clock
  // that would end the segment, and returns how many it did; its last clock
  // does not move the position (InterpCore::run_for); moved(i): the i-th
  // clock moved it.
  // Decoders may be settling an edge meanwhile (Let::settle).
  bool quiet_busy(const In& in, uint32_t n) const { return quiet_as(in, n, Let{false, true, true}); }
  template <typename Moved>
  uint32_t skip_busy(const In& in, uint32_t n, Moved&& moved) {
    return skip_busy_as(in, n, Let{false, true, true}, moved);
  }
  // The same after quiet_as(in, .., let), let.busy set.
  template <typename Moved>
  uint32_t skip_busy_as(const In& in, uint32_t n, Let let, Moved&& moved) {
    return skip_busy_as(in, n, let, moved, nullptr, 0);
  }
  using PinChange = mc::PinChange;
  // Of these changes (in clock order, each at clock 1 or later) inside a
  // stretch that quiet_as(in, .., let) allowed with let.settle, how many in
  // a row the stretch may take: each a clean edge of its decoder
  // (QuadDecoder::clean_edge_from) that finds the decoder settled, on the
  // pins before it, by its clock. Those settle as any edge does under
  // let.settle: only the count moves, which the PID reads at a tick. So a
  // stretch need not end at every count the plant reaches.
  size_t foldable(const In& in, const PinChange* ch, size_t count) const {
    // Per axis: the clock from which its decoder is settled, and on which
    // pins (asked of the decoder at its first change only).
    uint32_t ready[NAXES], pins[NAXES];
    bool known[NAXES] = {};
    for (size_t i = 0; i < count; ++i) {
      const PinChange& c = ch[i];
      QuadIn to = quad_in(in, c.axis, false);
      if (!known[c.axis]) {
        known[c.axis] = true;
        ready[c.axis] = dec_[c.axis].settle_clocks(to);
        pins[c.axis] = Decoder::pins_of(to);
      }
      to.a = c.a;
      to.b = c.b;
      to.z = c.z;
      if (ready[c.axis] == Decoder::kUnsettled || c.clock < ready[c.axis] ||
          !dec_[c.axis].clean_edge_from(pins[c.axis], to))
        return i;
      ready[c.axis] = c.clock + Decoder::kEdgeClocks;
      pins[c.axis] = Decoder::pins_of(to);
    }
    return count;
  }
  // skip_busy_as() with the pins changing as the first `count` of ch say
  // (all of them foldable(); those at or past the clocks it does are not
  // taken).
  template <typename Moved>
  uint32_t skip_busy_as(const In& in, uint32_t n, Let let, Moved&& moved, const PinChange* ch, size_t count) {
    if (tick_inside(let, n)) return skip_through_tick(in, n, let, moved, ch, count);
    return skip_stretch(in, n, let, moved, ch, count, 0);
  }
  uint32_t skip_busy(const In& in, uint32_t n) {
    return skip_busy(in, n, [](uint32_t) {});
  }

  void skip(uint32_t n) {
    skip_interp(n);
    skip_others(n, nullptr, Let{});
  }
  // The most clocks the sample timer and the sweep allow quiet(): up to the
  // next tick, drive update or done.
  // A running interpolator: up to its next iteration (with no input).
  uint32_t quiet_limit() const { return quiet_limit_as(Let{}); }
  // The same, for quiet_busy().
  uint32_t quiet_limit_busy() const { return quiet_limit_as(Let{false, true}); }
  // The same, for quiet_as(.., let): drive updates bound it unless
  // let.drive, the next iteration unless let.busy.
  uint32_t quiet_limit_as(Let let) const {
    uint32_t l = passes_tick(let) ? tick_limit() : pid_.quiet_limit(through_done(let)) + (let.sample ? 1 : 0);
    const int s = pid_.sweep_clock();
    if (s != 0 && !let.drive)
      for (int a = 0; a < NAXES; ++a)
        if (drv_clock(a) >= s && uint32_t(drv_clock(a) - s) < l) l = uint32_t(drv_clock(a) - s);
    if (!let.busy && ip_.state() == InterpCore<FIFO_AW>::ST_RUN) l = std::min(l, ip_.run_quiet(InterpIn{}));
    return l;
  }
  // A word of the published sample (what smp_raddr would read).
  int32_t sample(int a, SampleField f) const { return bank_[r_.pb][a][f]; }
  // The PWM counter's value in the current clock.
  uint32_t pwm_count() const { return r_.pcnt; }
  // Axis a's PWM pin after edges from .. from + n - 1 of a stretch that
  // quiet_as(in, .., let) allowed, each high pin counted -1 when DIR is set
  // with it, else +1 (what an H-bridge drives): the counter runs on, so the
  // count follows from the duty and the counter's phase (a host that
  // integrates the drive over a skipped stretch needs it; not RTL). The pin
  // after edge t is duty(u) > the counter in clock t and DIR is u < 0, u
  // the drive command then (zero unless allowed); with let.drive the
  // sweep's update comes in from drive_change() on. n < 2^31.
  int32_t drive_in(const In& in, int a, uint32_t from, uint32_t n) const {
    const uint32_t at = drive_change(in, a), end = from + n;
    const uint32_t split = std::clamp(at, from, end);
    const auto piece = [&](int16_t u, uint32_t t0, uint32_t len) {
      const int32_t high = int32_t(pwm_high_count((r_.pcnt + t0) & pwm_mask, duty(u), pwm_mask + 1, len));
      return u < 0 ? -high : high;
    };
    const int16_t now = u_sel(r_, in, a);
    if (split == end) return piece(now, from, n);
    return piece(now, from, split - from) + piece(updated(in, a), split, end - split);
  }
  // Of up to max runs of k >= 1 edges from edge `from` of such a stretch,
  // how many in a row leave axis a's PWM pin at one level throughout (0:
  // not the first), none reaching past drive_change() unless all after it.
  uint32_t drive_runs(const In& in, int a, uint32_t from, uint32_t k, uint32_t max) const {
    const uint32_t at = drive_change(in, a);
    const bool after = at != kNoChange && from >= at;
    const uint32_t d = duty(after ? updated(in, a) : u_sel(r_, in, a));
    constexpr uint32_t P = pwm_mask + 1;
    // The pin is high while the counter is below the duty: runs of k edges
    // go by until the counter crosses it, or wraps.
    const uint32_t c = (r_.pcnt + from) & pwm_mask;
    uint32_t r = d == 0 || d >= P ? max : (c < d ? d - c : P - c) / k;
    if (at != kNoChange && !after) r = std::min(r, (at - from) / k);
    return std::min(r, max);
  }
  // Axis a's drive value (drv_u) over the clocks of such a stretch: the
  // register's in its first clock, then the value it follows from the drive
  // command up to clock `change` (drive_change()), and the sweep's update
  // in the clocks after it.
  struct DriveSteps {
    int16_t first, then, after;
    uint32_t change;
    int16_t at(uint64_t clock) const { return clock == 0 ? first : clock <= change ? then : after; }
    // The first clock after c from which at() may differ (kNever: none).
    static constexpr uint64_t kNever = ~uint64_t(0);
    uint64_t next_change(uint64_t c) const {
      if (c == 0) return 1;
      return change != kNoChange && c <= change ? uint64_t(change) + 1 : kNever;
    }
  };
  DriveSteps drive_steps(const In& in, int a) const {
    return {r_.drv_u[a], u_sel(r_, in, a), updated(in, a), drive_change(in, a)};
  }
  // The clocks from this one over which drive_steps() tells the drive: up
  // to the first that the next sample's sweep updates.
  uint32_t known_drive_clocks() const {
    return (pid_.tick() ? 0 : pid_.timer()) + uint32_t(drv_clock(0)) + 2;
  }
  // The first edge of the stretch whose pin the sweep's drive update sets
  // (its clock's edge is the update, the next the drive value's), or
  // kNoChange.
  static constexpr uint32_t kNoChange = ~0u;
  uint32_t drive_change(const In& in, int a) const {
    const int s = pid_.sweep_clock();
    if (s == 0 || drv_clock(a) < s || in.drv_ovr[a]) return kNoChange;
    return uint32_t(drv_clock(a) - s) + 1;
  }

  const Pid& pid() const { return pid_; }
  using Interp = InterpCore<FIFO_AW>;
  const Interp& interp() const { return ip_; }
  const Decoder& decoder(int a) const { return dec_[a]; }
  // Single outputs of the current clock, for users that need a few of them
  // every clock (outputs() gathers all).
  bool pwm(int a) const { return r_.pwm[a]; }
  bool dir(int a) const { return r_.dir[a]; }
  bool drv_en(int a) const { return r_.drv_en[a]; }
  int16_t drv_cmd(int a) const { return r_.drv_cmd[a]; }
  int16_t drv_u(int a) const { return r_.drv_u[a]; }
  uint32_t smp_rdata() const { return r_.smp_rdata; }

 private:
  static constexpr uint32_t pwm_mask = (1u << PWM_BITS) - 1;

  static InterpIn interp_in(const In& in) {
    InterpIn ii;
    ii.wr = in.seg_wr;
    ii.wdata = in.seg_wdata;
    ii.abort = in.ip_abort;
    ii.hold = in.ip_hold;
    ii.clr = in.ip_clr;
    ii.set = in.ip_set;
    for (int a = 0; a < 3; ++a) ii.set_pos[a] = in.ip_set_pos[a];
    ii.jog = in.ip_jog;
    ii.jog_neg = in.ip_jog_neg;
    return ii;
  }
  bool interp_quiet(const In& in, uint32_t n, bool busy) const {
    const InterpIn ii = interp_in(in);
    // The interpolator idle, or running with no iteration due in the n
    // clocks (busy: with no input at all).
    if (ip_.quiet(ii)) return true;
    if (busy)
      return ip_.state() == InterpCore<FIFO_AW>::ST_RUN && !ii.wr && !ii.abort && !ii.hold && !ii.clr &&
             !ii.set && !ii.jog;
    return ip_.run_quiet(ii) >= n;
  }
  bool quiet_but_interp(const In& in, uint32_t n, Let let, bool pid_own = false) const {
    const typename Pid::In pi = pid_in(in, nullptr, nullptr);
    return quiet_but_pid_interp(in, n, let) &&
           (pid_own ? n == 1 && pid_.quiet_but_timers(pi) : pid_quiet(pi, n, let));
  }
  // quiet_but_interp() without the PID's own part.
  bool quiet_but_pid_interp(const In& in, uint32_t n, Let let) const {
    if (in.rst || in.pid_we || in.pid_re || n == 0) return false;
    if (pid_.sweep_clock() != 0 &&
        !let.drive) {  // inside a sweep: no axis takes its new drive value in the n clocks
      const int s = pid_.sweep_clock();
      for (int a = 0; a < NAXES; ++a)
        if (drv_clock(a) >= s && uint32_t(drv_clock(a) - s) < n && !in.drv_ovr[a]) return false;
    }
    if (!let.port && !let.sample && r_.smp_rdata != read_bank(in.smp_raddr)) return false;
    for (int a = 0; a < NAXES; ++a) {
      const QuadIn qi = quad_in(in, a, false);
      if (!(let.settle ? dec_[a].settle_clocks(qi) != Decoder::kUnsettled : dec_[a].quiet(qi)) ||
          in.drv_ovr_we[a])
        return false;
      if ((!let.drive && r_.drv_u[a] != u_sel(r_, in, a)) || r_.drv_en[a] != drv_en(in, a)) return false;
    }
    return true;
  }
  void skip_interp(uint32_t n) {
    if (ip_.state() == InterpCore<FIFO_AW>::ST_RUN) {
      ip_.skip_run(n);
    } else if (ip_still_ < 2) {
      ip_.skip(n);
      ip_still_ = n < 2 ? uint8_t(ip_still_ + n) : 2;
    }
  }
  // A stretch without the tick; ch's clocks count from `from`.
  template <typename Moved>
  uint32_t skip_stretch(const In& in, uint32_t n, Let let, Moved&& moved, const PinChange* ch, size_t count,
                        uint32_t from) {
    if (ip_.state() == InterpCore<FIFO_AW>::ST_RUN) {
      n = ip_.run_for(n, moved);
      if (n == 0) return 0;
    } else {
      skip_interp(n);
    }
    skip_others(n, &in, let, ch, count, from);
    return n;
  }
  // Stretches under let may go through the tick, which is not this clock:
  // it comes after pid_.timer() clocks.
  bool passes_tick(Let let) const { return let.tick && through_done(let) && !pid_.tick(); }
  // The longest of them: up to the new sweep's first drive command.
  uint32_t tick_limit() const { return pid_.timer() + uint32_t(drv_clock(0)); }
  // A stretch of n clocks under let goes through the tick.
  bool tick_inside(Let let, uint32_t n) const { return passes_tick(let) && pid_.timer() < n; }
  // The PID's part of the checks: through the tick (its port idle, the
  // stretch within tick_limit()), else the timers' bound.
  bool pid_quiet(const typename Pid::In& pi, uint32_t n, Let let) const {
    if (tick_inside(let, n)) return pid_.quiet_but_timers(pi) && !pid_.rvalid() && n <= tick_limit();
    return pid_.quiet(pi, n, let.sample, through_done(let));
  }
  // skip_busy_as() through the tick: the stretch before it, the tick's
  // clock clocked with the pins the changes give it, the stretch after.
  template <typename Moved>
  uint32_t skip_through_tick(const In& in, uint32_t n, Let let, Moved& moved, const PinChange* ch,
                             size_t count) {
    const uint32_t t = pid_.timer();
    size_t k = 0;
    while (k < count && ch[k].clock < t) ++k;
    if (const uint32_t m = t > 0 ? skip_stretch(in, t, let, moved, ch, k, 0) : 0; m < t) return m;
    if (ip_.ending()) return t;
    In at = in;
    for (k = 0; k < count && ch[k].clock <= t; ++k) {
      at.enc_a[ch[k].axis] = ch[k].a;
      at.enc_b[ch[k].axis] = ch[k].b;
      at.enc_z[ch[k].axis] = ch[k].z;
    }
    int32_t was[NAXES];
    for (int a = 0; a < NAXES; ++a) was[a] = ip_.pos(a);
    clock(at);
    for (int a = 0; a < NAXES; ++a)
      if (ip_.pos(a) != was[a]) {
        moved(t + 1);
        break;
      }
    if (n == t + 1) return n;
    const auto after = [&moved, t](uint32_t i) { moved(t + 1 + i); };
    return t + 1 + skip_stretch(at, n - t - 1, let, after, ch + k, count - k, t + 1);
  }
  // in: the inputs held (needed with let.settle or let.drive), but for the
  // pins that ch changes (let.settle): ch's clocks count from the
  // stretch's first, these n clocks its from-th on, the changes before them
  // giving the pins they start with.
  void skip_others(uint32_t n, const In* in, Let let, const PinChange* ch = nullptr, size_t count = 0,
                   uint32_t from = 0) {
    if (let.drive) skip_drive(n, *in);
    // The port reads the published bank as the last clock found it: done
    // swaps it at its edge (let.done).
    const uint32_t d = through_done(let) ? pid_.done_in() : Pid::kNoDone;
    if (let.sample && d + 1 == n) r_.smp_rdata = read_bank(in->smp_raddr);
    if (d < n) publish(r_);
    if (let.sample && d + 1 != n) r_.smp_rdata = read_bank(in->smp_raddr);
    pid_.skip(n);
    for (int a = 0; a < NAXES; ++a) {
      if (let.settle) {
        QuadIn qi = quad_in(*in, a, false);
        uint32_t t = 0;
        for (size_t i = 0; i < count && ch[i].clock < from + n; ++i) {
          if (ch[i].axis != a) continue;
          if (ch[i].clock > from) {
            dec_[a].skip_settling(qi, ch[i].clock - from - t);
            t = ch[i].clock - from;
          }
          qi.a = ch[i].a;
          qi.b = ch[i].b;
          qi.z = ch[i].z;
        }
        dec_[a].skip_settling(qi, n - t);
      } else {
        dec_[a].skip(n);
      }
      r_.pwm[a] = duty(r_.drv_u[a]) > ((r_.pcnt + n - 1) & pwm_mask);
    }
    r_.pcnt = (r_.pcnt + n) & pwm_mask;
  }

  // The sweep's output for axis a, which its drive command takes, and the
  // drive value it gives (zero unless the drive is allowed).
  int16_t update(int a) const { return int16_t(pid_.core().u(a)); }
  int16_t updated(const In& in, int a) const { return in.drv_allow[a] ? update(a) : int16_t(0); }
  // The drive stage over n clocks with the sweep's updates (before the
  // timers move): the drive command the last edge leaves, and the value
  // and DIR registered from the command of the last clock (skip_others
  // sets PWM from that value).
  void skip_drive(uint32_t n, const In& in) {
    for (int a = 0; a < NAXES; ++a) {
      const uint32_t at = drive_change(in, a);  // the edge after the update's
      const int16_t before = u_sel(r_, in, a);
      if (at <= n) r_.drv_cmd[a] = update(a);
      const int16_t u = at < n ? updated(in, a) : before;
      r_.drv_u[a] = u;
      r_.dir[a] = u < 0;
    }
  }

  uint32_t read_bank(uint8_t raddr) const { return uint32_t(bank_[r_.pb][raddr >> 3 & 3][raddr & 7]); }
  static bool through_done(Let let) { return let.sample && let.done; }
  struct Regs;
  // Done's edge (no reset), from r, the registers of its clock: the sample
  // into the bank not published, which it then publishes, and the
  // saturation flags. The RTL's sweep fills that bank word by word; only
  // the published bank is ever read, so writing the words at done is the
  // same to every reader.
  void publish(const Regs& r) {
    const bool pb = r.pb;
    for (int a = 0; a < NAXES; ++a) {
      int32_t* w = bank_[!pb][a];
      w[SMP_CMD] = r.in_cmd[a];
      w[SMP_FB] = r.in_fb[a];
      w[SMP_ERR] = pid_.core().err(a);
      w[SMP_OUT] = int32_t(uint32_t(uint16_t(pid_.core().u(a))) | uint32_t(pid_.core().sat(a)) << 16 |
                           uint32_t(pid_.enabled(a)) << 17);
      const int64_t follow = int64_t(r.in_cmd[a]) - r.in_fb[a];
      w[SMP_FOLLOW] = int32_t(std::clamp<int64_t>(follow, INT32_MIN, INT32_MAX));
      r_.smp_sat[a] = pid_.core().sat(a);
    }
    r_.pb = !pb;
  }
  static int16_t u_sel(const Regs& r, const In& in, int a) {
    return !in.drv_allow[a] ? int16_t(0) : r.drv_cmd[a];
  }
  bool drv_en(const In& in, int a) const { return in.drv_allow[a] && (pid_.enabled(a) || in.drv_ovr[a]); }
  static typename Pid::In pid_in(const In& in, const int32_t* cmd, const int32_t* fb) {
    typename Pid::In pi;
    pi.rst = in.rst;
    pi.we = in.pid_we;
    pi.waddr = in.pid_waddr;
    pi.wdata = in.pid_wdata;
    pi.re = in.pid_re;
    pi.raddr = in.pid_raddr;
    pi.cmd = cmd;
    pi.fb = fb;
    return pi;
  }
  static QuadIn quad_in(const In& in, int a, bool tick) {
    QuadIn qi;
    qi.rst = in.rst;
    qi.filt_len = in.enc_filt[a];
    qi.dir_inv = in.enc_dir_inv[a];
    qi.idx_clr_en = in.enc_idx_clr_en[a];
    qi.idx_arm = in.enc_idx_arm[a];
    qi.idx_disarm = in.enc_idx_disarm[a];
    qi.err_clr = in.enc_err_clr[a];
    qi.sample = tick;
    qi.a = in.enc_a[a];
    qi.b = in.enc_b[a];
    qi.z = in.enc_z[a];
    qi.latch = in.enc_latch[a];
    return qi;
  }

  struct Regs {
    bool operator==(const Regs&) const = default;
    int32_t in_cmd[NAXES] = {}, in_fb[NAXES] = {};
    bool pb = false;
    uint32_t smp_rdata = 0;
    int16_t drv_cmd[NAXES] = {};
    bool smp_sat[NAXES] = {};
    uint32_t pcnt = 0;
    int16_t drv_u[NAXES] = {};
    bool pwm[NAXES] = {}, dir[NAXES] = {}, drv_en[NAXES] = {};
  };
  int32_t bank_[2][4][SMP_FIELDS] = {};  // the sample RAM: [bank][axis][field], as the RTL's 64 words
  Pid pid_;
  InterpCore<FIFO_AW> ip_;
  uint8_t ip_still_ = 0;  // quiet interpolator clocks in a row, up to 2
  Decoder dec_[NAXES];
  Regs r_;
};

}  // namespace mc
