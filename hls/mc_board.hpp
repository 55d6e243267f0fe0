// mc_board twin: the portable board core, clock by clock: motion_core plus
// the link (uart_rx, uart_tx, link_rx, link_tx), the register file
// (mc_regs), the safety logic (mc_safety), the machine I/O (mc_io), the
// stepper axes (mc_step), the handwheel decoder and the LEDs. Mirrors rtl/mc_board.v, which documents how to
// use it; the pins reach it through the board top (hls/motioncore_icebreaker.hpp).
//
// The sub-blocks are the twins of the RTL's instances, named as the RTL
// names them, and wired as it wires them: clock() first takes every wire of
// the current clock from the registers, then clocks each block on them.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
#pragma once

#include <cstdint>

#include "crc16_ccitt.hpp"
#include "link_rx.hpp"
#include "link_tx.hpp"
#include "mc_io.hpp"
#include "mc_regs.hpp"
#include "mc_safety.hpp"
#include "mc_step.hpp"
#include "motion_core.hpp"
#include "quad_decoder.hpp"
#include "uart_rx.hpp"
#include "uart_tx.hpp"

namespace mc {

// Inputs of one clock. Per-axis pins are bit masks, bit a for axis a.
struct McBoardIn {
  bool operator==(const McBoardIn&) const = default;
  bool rst = false;
  bool rx = true;                           // synchronized
  uint8_t enc_a = 0, enc_b = 0, enc_z = 0;  // asynchronous: the decoders synchronize them
  bool hw_a = false, hw_b = false;
  uint8_t lim = 0;                   // synchronized
  bool estop = false, stop = false;  // synchronized
  bool probe = false;                // synchronized
};

template <int NAXES = 3, int FIFO_AW = 9, int PWM_BITS = 9, int FILT_W = 4, int CLK_HZ = 12'000'000,
          int BAUD = 1'000'000, bool HANDWHEEL = true, int STEPPERS = 0, bool SERVO = true>
class McBoard {
 public:
  using Core = MotionCore<NAXES, FIFO_AW, PWM_BITS, FILT_W, true, SERVO>;  // IDX_RAM: as the board builds it
  using PinChange = mc::PinChange;
  using Regs = McRegs<NAXES, FIFO_AW, FILT_W, CLK_HZ, BAUD, STEPPERS, SERVO, HANDWHEEL>;
  using Safety = McSafety<NAXES>;
  using Io = McIo<NAXES>;
  using Step = McStep<NAXES, STEPPERS>;
  using Handwheel = QuadDecoder<FILT_W, 2, 2, 2, false, false>;  // position only, no load
  static constexpr int HB_W = clog2(CLK_HZ);                     // heartbeat counter bits
  static constexpr uint8_t AXES = (1u << NAXES) - 1;

  UartRx<CLK_HZ, BAUD> u_urx;
  UartTx<CLK_HZ, BAUD> u_utx;
  LinkRx<CLK_HZ> u_lrx;
  LinkTx u_ltx;
  Regs u_regs;
  Safety u_safety;
  Core u_core;
  Io u_io;
  Step u_step;
  Handwheel u_hw;  // unused without HANDWHEEL
  uint32_t hb = 0;

  // ---- outputs (all from registers) ----------------------------------------
  bool tx_o() const { return u_utx.tx_o; }
  bool pwm_o(int a) const { return u_step.pwm_o(a, u_core.pwm(a)); }
  bool dir_o(int a) const { return u_step.dir_o(a, u_core.dir(a)); }
  // A stepper axis's driver is enabled while the drives are armed.
  bool drv_en_o(int a) const { return u_core.drv_en(a) || (u_safety.armed_o && (u_step.stepper >> a & 1)); }
  bool sp_pwm_o() const { return u_io.r.sp_pwm_o; }
  bool sp_en_o() const { return u_io.r.sp_en_o; }
  bool sp_dir_o() const { return u_io.r.sp_dir_o; }
  bool flood_o() const { return u_io.r.flood_o; }
  bool mist_o() const { return u_io.r.mist_o; }
  bool led_fault_o() const { return u_safety.fault_o != 0; }
  bool led_ok_o() const { return u_safety.armed_o || (!led_fault_o() && (hb >> (HB_W - 1) & 1)); }

  // ---- one clock edge ------------------------------------------------------
  void clock(const McBoardIn& in) {
    Wires& w = w_;
    // quiet() just computed them from this state and these inputs.
    if (!wired_ || !(in == wired_in_)) wires(in, w);
    wired_ = false;
    walk_ = 0;
    let_ = {};
    sending_ = false;
    const uint8_t tx_byte = u_ltx.byte_o;
    const bool tx_valid = u_ltx.valid_o;
    u_urx.clock(in.rst, in.rx);
    u_utx.clock(in.rst, tx_byte, tx_valid);
    u_lrx.clock(w.lrx);
    u_ltx.clock(w.ltx);
    regs_changed_ = u_regs.clock(w.regs);
    u_safety.clock(w.safety);
    u_core.clock(core_in_);
    u_io.clock(w.io);
    u_step.clock(w.step);
    if constexpr (HANDWHEEL) {
      if (u_hw.quiet(w.hw))
        u_hw.skip(1);  // settled: the same as step(), for less work
      else
        u_hw.step(w.hw);
    }
    hb = (hb + 1) & ((1u << HB_W) - 1);
    if (in.rst) hb = 0;
  }

  // ---- fast-forward ----------------------------------------------------------
  // Clocks (up to limit) with these inputs held that change nothing but
  // counters and timers, TX's bits, a frame going out (link_tx and uart_tx
  // on their own: send), a decoder settling an edge and the PID sweep's
  // drive updates (MotionCore::Let): the receiver idle or inside a bit, the
  // link idle or waiting (for the next byte of a frame before the timeout,
  // for uart_tx), no frame being parsed or answered, no tick or done, no
  // fault. skip(n) then does n of them at once, leaving exactly the state
  // of n clocks; 0 means clock() this one.
  uint32_t quiet(const McBoardIn& in, uint32_t limit) { return quiet_but_rx(in, u_urx.quiet(in.rx, limit)); }
  // The same inside a byte on RX, with the line's future known (rx(t):
  // in.rx in the t-th clock from now): the stretch goes on through the
  // byte's samples, up to its stop bit's. skip_line(n, rx) does it (not RTL).
  template <typename Rx>
  uint32_t quiet_line(const McBoardIn& in, uint32_t limit, Rx&& rx) {
    return quiet_but_rx(in, u_urx.quiet_line(rx, limit));
  }
  // quiet() after the receiver's n (0 for a limit of 0).
  uint32_t quiet_but_rx(const McBoardIn& in, uint32_t n) {
    walk_ = 0;
    let_ = {};
    sending_ = false;
    // The PID's tick or done in this clock ends every stretch (the board's
    // skips do not go through them: quiet_limit_as below): found here, the
    // two clocks of a sample that are always clocked skip the checks.
    if (n == 0 || in.rst || u_core.pid().tick() || u_core.pid().done()) return 0;
    // A frame on its way out (link_tx busy) goes on inside the stretch
    // (sending_, below); otherwise uart_tx is idle, and a byte handed to it
    // ends the stretch.
    if (!u_ltx.busy_o()) n = u_utx.quiet(u_ltx.valid_o, n);
    if (n == 0 || u_regs.r.xs != Regs::X_IDLE) return 0;
    if (u_lrx.st == u_lrx.S_HUNT && (u_lrx.idle != 0 || !u_lrx.u_crc.at_init())) return 0;
    Wires& w = w_;
    wires(in, w);
    wired_ = true;
    wired_in_ = in;
    n = u_lrx.quiet(w.lrx, n);
    // The walker reading a sample with no telemetry to send: it may run
    // inside the stretch (walk_clocks).
    const bool walking = !u_regs.walk_settled(w.regs);
    sending_ = u_ltx.busy_o() && !w.ltx.we && !w.ltx.start;
    if (n == 0 || !(sending_ || u_ltx.quiet(w.ltx)) || !u_regs.quiet_but_walk(w.regs) ||
        (walking && !u_regs.walk_silent()))
      return 0;
    n = u_safety.quiet(w.safety, n);
    // A running segment may go on inside the stretch while its command
    // reaches nothing but the PID's next tick: no step generator armed.
    const bool busy = u_core.interp().state() == Core::Interp::ST_RUN && u_step.following(w.step);
    // The sweep's drive updates may come inside unless the register file
    // reads a drive command back (its read pipeline follows it). Unless a
    // walk moves the sample port, the stretch may end with the edge that
    // raises the tick or done (which reach the other blocks a clock later;
    // the port reads the same word through it).
    let_ = typename Core::Let{walking, busy, true, !u_regs.reads_drive(), !walking};
    // No tick or done in the n clocks, the last at most raising one (nor a
    // drive update, unless let_.drive; nor, unless busy, an iteration).
    const uint32_t t = u_core.quiet_limit_as(let_);
    if (t < n) n = t;
    if (n == 0 || !u_core.quiet_as(core_in_, n, let_)) return 0;
    if (!u_io.quiet(w.io) || !u_step.quiet(w.step)) return 0;
    if constexpr (HANDWHEEL)
      if (!u_hw.quiet(w.hw)) return 0;
    if (walking && (walk_ = walk_clocks(w.regs)) == 0) return 0;
    if (busy && u_core.interp().end_bound() < n) {
      // Up to the clock that would end the segment (a copy finds it).
      typename Core::Interp ip = u_core.interp();
      n = ip.run_to_end(n);
    }
    if (sending_) {
      // Up to the clock in which the frame's end frees link_tx, the register
      // file seeing it busy until then (copies find it).
      LinkTx l = u_ltx;
      UartTx<CLK_HZ, BAUD> u = u_utx;
      n = send(l, u, w.ltx, n, [](bool, uint32_t) {});
    }
    return n;
  }
  // The line after each of the next n clocks of the stretch quiet() found,
  // as runs: f(level, clocks), the clocks adding up to n.
  template <typename F>
  void tx_levels(uint32_t n, F&& f) const {
    if (!sending_) {
      u_utx.levels(n, f);
      return;
    }
    LinkTx l = u_ltx;
    UartTx<CLK_HZ, BAUD> u = u_utx;
    send(l, u, w_.ltx, n, f);
  }
  // A walk on its own: the register file clocked with the other blocks
  // quiet, the sample RAM's read port following its address as
  // motion_core's does. The clocks until the walker is idle and its read
  // pipeline settled; 0 when the walk would show outside the register file
  // (a following-error trip, a telemetry word or frame), which a skip must
  // not hide.
  // The register file at the walk's end is kept for skip() (walked_).
  // quiet() found quiet_but_walk(in) before, and a walk keeps it: of what
  // that reads, the walker's part of a clock sets only ferr_o, tx_start_o
  // and tlm_pend, each of which ends the walk here; quiet() refused a walk
  // with telemetry due (walk_silent). So each clock of it is a
  // walk_clock(), and it is over once the walker has settled.
  uint32_t walk_clocks(const typename Regs::In& in) {
    Regs& regs = walked_;
    regs = u_regs;
    typename Regs::In ri = in;
    uint32_t port = u_core.smp_rdata();
    for (uint32_t c = 1; c <= kMaxWalk; ++c) {
      ri.smp_rdata = port;
      walked_raddr_ = regs.smp_raddr_o();
      walked_changed_ = regs.walk_clock(ri);
      port = u_core.port_word(walked_raddr_);
      if (regs.r.ferr_o != 0 || regs.r.tx_start_o || regs.r.tlm_pend || regs.tx_we_o()) return 0;
      ri.smp_rdata = port;
      if (regs.walk_settled(ri) && port == u_core.port_word(regs.smp_raddr_o())) return c;
    }
    return 0;
  }
  // The stretch may take encoder edges: pins changing as ch says (in clock
  // order, each at clock 1 or later), the first `count` of them those that
  // foldable() allowed.
  void skip(uint32_t n, const PinChange* ch = nullptr, size_t count = 0) {
    u_urx.skip(n);
    skip_but_rx(n, ch, count);
  }
  // Of these encoder pins' changes inside the stretch quiet() found, how
  // many in a row it may take: edges its decoders settle cleanly
  // (Core::foldable; the stretch lets them settle), on axes whose decoder
  // counts the pins (not an open-loop stepper's). Each moves only a count,
  // which the PID reads at a tick and no stretch goes through (nor does the
  // register file read it live: positions come from the sample RAM).
  size_t foldable(const PinChange* ch, size_t count) const {
    for (size_t i = 0; i < count; ++i)
      if (u_step.stepper >> ch[i].axis & 1) {
        count = i;
        break;
      }
    return u_core.foldable(core_in_, ch, count);
  }
  // Over the pins after edges from .. from + n - 1 of the stretch quiet()
  // found (before skip()): axis a's PWM (STEP) pin high, counted -1 with
  // DIR set, else +1. A stepper's pins hold; a servo's drive takes the
  // sweep's update at drive_change(a) (Core::drive_change; kNoChange: none).
  int32_t drive_in(int a, uint32_t from, uint32_t n) const {
    if (u_step.stepper >> a & 1) return pwm_o(a) ? (dir_o(a) ? -int32_t(n) : int32_t(n)) : 0;
    return u_core.drive_in(core_in_, a, from, n);
  }
  uint32_t drive_runs(int a, uint32_t from, uint32_t k, uint32_t max) const {
    if (u_step.stepper >> a & 1) return max;
    return u_core.drive_runs(core_in_, a, from, k, max);
  }
  uint32_t drive_change(int a) const {
    if ((u_step.stepper >> a & 1) || !let_.drive) return Core::kNoChange;
    return u_core.drive_change(core_in_, a);
  }
  template <typename Rx>
  void skip_line(uint32_t n, Rx&& rx, const PinChange* ch = nullptr, size_t count = 0) {
    u_urx.skip_line(n, rx);
    skip_but_rx(n, ch, count);
  }
  void skip_but_rx(uint32_t n, const PinChange* ch = nullptr, size_t count = 0) {
    wired_ = false;
    if (walk_ > 0 && n >= walk_) {  // quiet() found a walk that ends in the stretch: its end
      u_regs = walked_;
      u_core.read_port(walked_raddr_);
      regs_changed_ = walked_changed_;
      walk_ = 0;
    } else if (walk_ > 0) {  // part of it: the register file and the port it reads, clock by clock
      typename Regs::In ri = w_.regs;
      for (uint32_t i = 0; i < n; ++i) {
        ri.smp_rdata = u_core.smp_rdata();
        const uint8_t raddr = u_regs.smp_raddr_o();
        regs_changed_ = u_regs.clock(ri);
        u_core.read_port(raddr);
      }
      walk_ -= n;
    }
    if (sending_) {
      send(u_ltx, u_utx, w_.ltx, n, [](bool, uint32_t) {});
    } else {
      u_utx.skip(n);
      u_ltx.skip(n);
    }
    u_lrx.skip(n);
    u_safety.skip(n);
    if (let_.busy) {
      // quiet() found at least n clocks before the segment's end. The step
      // generators take the command their last clock showed: after all
      // edges but the last.
      if (n > 1) u_core.skip_as(core_in_, n - 1, let_, ch, count);
      uint8_t cmd = 0;
      for (int a = 0; a < NAXES; ++a) cmd = uint8_t(cmd | (uint32_t(u_core.interp().pos(a)) & 3) << (2 * a));
      u_core.skip_as(core_in_, 1, let_, ch, count, n - 1);  // on the pins the edges before it left
      u_step.follow(cmd);
    } else {
      u_core.skip_as(core_in_, n, let_, ch, count);
    }
    u_io.skip(n, u_safety.armed_o);
    if constexpr (HANDWHEEL) u_hw.skip(n);
    hb = (hb + n) & ((1u << HB_W) - 1);
  }

 private:
  // The frame going out (link_tx busy) over up to n clocks with link_tx's
  // inputs held but uart_tx's ready: the two blocks on their own, as clock()
  // clocks them (uart_tx takes the byte link_tx showed, link_tx sees the
  // ready of the clock before), the bits of a byte at once. Stops after the
  // clock that frees link_tx; f(level, clocks) tells TX after each clock,
  // as runs. Returns the clocks done.
  template <typename F>
  static uint32_t send(LinkTx& l, UartTx<CLK_HZ, BAUD>& u, LinkTxIn in, uint32_t n, F&& f) {
    uint32_t c = 0;
    while (c < n && l.busy_o()) {
      in.ready = u.ready_o();
      if (const uint32_t m = l.quiet(in) ? u.quiet(l.valid_o, n - c) : 0; m > 0) {  // a byte's bits
        u.levels(m, f);
        u.skip(m);
        l.skip(m);
        c += m;
        continue;
      }
      const uint8_t byte = l.byte_o;
      const bool valid = l.valid_o;
      u.clock(false, byte, valid);
      l.clock(in);
      f(u.tx_o, 1u);
      ++c;
    }
    return c;
  }

  // The wires of the current clock: every block's inputs.
  struct Wires {
    LinkRxIn lrx;
    LinkTxIn ltx;
    typename Regs::In regs;
    McSafetyIn safety;
    McIoIn io;
    McStepIn step;
    QuadIn hw;
  };

  void wires(const McBoardIn& in, Wires& w) {
    const auto& rr = u_regs.r;
    const bool armed = u_safety.armed_o;
    const bool pid_we = u_regs.pid_we_o(in.rst);
    const uint32_t data = rr.data;

    // Link.
    w.lrx.rst = in.rst;
    w.lrx.byte = u_urx.data_o;
    w.lrx.valid = u_urx.valid_o;
    w.lrx.ferr = u_urx.ferr_o;
    w.lrx.pay_raddr = u_regs.pay_raddr_o();

    // Safety.
    McSafetyIn& s = w.safety;
    s.rst = in.rst;
    s.arm_set = rr.arm_set_o;
    s.arm_clr = rr.arm_clr_o;
    s.clr = rr.fclr_o;
    s.cfg = rr.safety_o;
    s.wdog = rr.wdog_o;
    s.estop = in.estop;
    s.stop = in.stop;
    s.lim = uint8_t(in.lim & AXES);
    s.ferr = uint8_t(rr.ferr_o | u_step.ferr_o());

    // motion_core: the pins every clock; what comes from the register file
    // and the arm state only when either may have changed (the register
    // file's idle clocks change nothing).
    // Stepper axes: the generators take the command's low bits; an
    // open-loop axis's decoder counts the steps sent instead of its pins.
    McStepIn& st = w.step;
    st.rst = in.rst;
    st.bus_we = u_regs.bus_we_o();
    st.bus_addr = u_regs.bus_addr_o();
    st.bus_wdata = data;
    st.cmd = 0;
    for (int a = 0; a < NAXES; ++a)
      st.cmd = uint8_t(st.cmd | (uint32_t(u_core.interp().pos(a)) & 3) << (2 * a));
    st.sync = uint8_t(u_regs.ip_set_o() & AXES);
    st.allow = armed;
    st.clr = uint8_t(rr.fclr_o >> board::bits::F_FERR_LSB & AXES);
    st.enc_a = uint8_t(in.enc_a & AXES);
    st.enc_b = uint8_t(in.enc_b & AXES);
    const uint8_t qa = u_step.enc_a_o(st.enc_a), qb = u_step.enc_b_o(st.enc_b);

    // motion_core: the pins and the I/O block's strobes every clock; what
    // comes from the register file and the arm state only when either may
    // have changed (the register file's idle clocks change nothing).
    const auto& io = u_io.r;
    MotionIn<NAXES>& m = core_in_;
    for (int a = 0; a < NAXES; ++a) {
      m.enc_a[a] = qa >> a & 1;
      m.enc_b[a] = qb >> a & 1;
      m.enc_z[a] = in.enc_z >> a & 1;
      m.enc_latch[a] = io.latch_o >> a & 1;
    }
    m.ip_jog = io.jog_o;
    m.ip_jog_neg = io.jog_neg_o;
    m.ip_abort = rr.ip_abort_o || io.stop_o;
    if (regs_changed_ || in.rst != m.rst || armed != m.drv_allow[0]) {
      m.rst = in.rst;
      m.pid_we = pid_we;
      m.pid_waddr = m.pid_raddr = u_regs.pid_addr_o();
      m.pid_wdata = data;
      m.pid_re = u_regs.pid_re_o();
      m.seg_wr = rr.seg_wr_o;
      m.seg_wdata = data;
      m.ip_hold = rr.ip_hold_o || !armed;
      m.ip_clr = rr.ip_clr_o;
      m.ip_set = u_regs.ip_set_o();
      for (int32_t& p : m.ip_set_pos) p = int32_t(u_regs.ip_set_val_o());
      m.drv_ovr_val = int16_t(u_regs.drv_ovr_val_o());
      m.smp_raddr = u_regs.smp_raddr_o();
      for (int a = 0; a < NAXES; ++a) {
        m.enc_filt[a] = rr.enc_filt_o[a];
        m.enc_dir_inv[a] = rr.enc_dir_inv_o >> a & 1;
        m.enc_idx_clr_en[a] = rr.enc_idx_clr_en_o >> a & 1;
        m.enc_idx_arm[a] = rr.enc_idx_arm_o >> a & 1;
        m.enc_idx_disarm[a] = rr.enc_idx_disarm_o >> a & 1;
        m.enc_err_clr[a] = rr.enc_err_clr_o >> a & 1;
        m.drv_allow[a] = armed;
        m.drv_ovr[a] = rr.drv_ovr_o >> a & 1;
        m.drv_ovr_we[a] = rr.drv_ovr_we_o >> a & 1;
      }
    }

    // The register file's inputs. Of the per-axis words only the axis its
    // read address names is read (the others are left as they were).
    typename Regs::In& ri = w.regs;
    ri.rst = in.rst;
    ri.frame = u_lrx.frame_o;
    ri.seq = u_lrx.seq_o;
    ri.cmd = u_lrx.cmd_o;
    ri.len = u_lrx.len_o;
    ri.pay_rdata = u_lrx.pay_rdata_o;
    ri.crc_err = u_lrx.crc_err_o;
    ri.framing = u_lrx.framing_o;
    ri.junk = u_lrx.junk_o;
    ri.tx_busy = u_ltx.busy_o();
    ri.fault = u_safety.fault_o;
    ri.armed = armed;
    const auto& pid = u_core.pid();
    ri.pid_wready = pid.wready();
    ri.pid_rready = pid.rready(pid_we);
    ri.pid_rvalid = pid.rvalid();
    ri.pid_rdata = pid.rdata();
    const auto& ip = u_core.interp();
    ri.seg_count = uint32_t(ip.count());
    ri.ip_busy = ip.busy();
    ri.ip_underrun = ip.underrun();
    ri.ip_ovf = ip.ovf();
    ri.ip_seg_cnt = uint16_t(ip.seg_cnt());
    uint32_t err = 0, armd = 0, seen = 0, den = 0, pen = 0;
    for (int a = 0; a < NAXES; ++a) {
      const auto& d = u_core.decoder(a);
      err |= uint32_t(d.err()) << a;
      armd |= uint32_t(d.idx_armed()) << a;
      seen |= uint32_t(d.idx_seen()) << a;
      den |= uint32_t(drv_en_o(a)) << a;  // a stepper's enable too
      pen |= uint32_t(pid.enabled(a)) << a;
    }
    ri.enc_err = uint8_t(err);
    ri.enc_idx_armed = uint8_t(armd);
    ri.enc_idx_seen = uint8_t(seen);
    ri.drv_en = uint8_t(den);
    ri.pid_en = uint8_t(pen);
    const int ra = rr.ra >> 4 & 3;
    if (ra < NAXES) {
      const auto& d = u_core.decoder(ra);
      ri.enc_err_cnt[ra] = uint8_t(d.err_cnt());
      ri.enc_idx_pos[ra] = uint32_t(d.idx_pos());
      ri.drv_sel[ra] = armed ? uint16_t(u_core.drv_cmd(ra)) : 0;  // drv_allow low selects 0
    }
    ri.done = pid.done();
    ri.smp_rdata = u_core.smp_rdata();
    ri.hw_pos = HANDWHEEL ? uint32_t(u_hw.pos()) : 0;
    ri.io_stat = u_io.stat_o() | uint32_t(u_step.err_o()) << board::bits::IOS_STEP_ERR_LSB;
    s.enc_err = ri.enc_err;
    s.kick = u_regs.kick_o(ri);
    ri.estop_act = u_safety.estop_act_o(s);
    ri.lim_act = u_safety.lim_act_o(s);

    // link_tx: the register file's words and header fields.
    LinkTxIn& t = w.ltx;
    t.rst = in.rst;
    t.we = u_regs.tx_we_o();
    t.waddr = u_regs.tx_waddr_o();
    t.wdata = u_regs.tx_wdata_o(ri);
    t.start = rr.tx_start_o;
    t.seq = rr.tx_seq_o;
    t.cmd = rr.tx_cmd_o;
    t.status_en = rr.tx_status_en_o;
    t.status = rr.tx_status_o;
    t.wbase = rr.tx_wbase_o;
    t.nwords = rr.tx_nwords_o;
    t.ready = u_utx.ready_o();

    // Machine I/O.
    McIoIn& io_in = w.io;
    io_in.rst = in.rst;
    io_in.bus_we = st.bus_we;
    io_in.bus_addr = st.bus_addr;
    io_in.bus_wdata = data;
    io_in.armed = armed;
    io_in.lim_inv = uint8_t(rr.safety_o >> board::bits::S_LIM_INV_LSB & AXES);
    io_in.lim = uint8_t(in.lim & AXES);
    io_in.probe = in.probe;
    io_in.idx_armed = ri.enc_idx_armed;
    io_in.ip_idle = !ip.busy() && ip.count() == 0;
    io_in.hw_pos = uint8_t(ri.hw_pos);

    // Handwheel.
    QuadIn& h = w.hw;
    h.rst = in.rst;
    h.filt_len = rr.hw_filt_o;
    h.dir_inv = rr.hw_dir_inv_o;
    h.a = in.hw_a;
    h.b = in.hw_b;
  }

  // Kept from clock to clock rather than built anew (every field read is
  // written by wires()).
  Wires w_;
  MotionIn<NAXES> core_in_;
  bool regs_changed_ = true;  // the register file's last clock may have changed its outputs
  // w_ holds the wires of this state for wired_in_ (quiet() computed them):
  // a clock() with the same inputs that follows takes them as they are.
  bool wired_ = false;
  bool sending_ = false;  // quiet() found a frame going out inside the stretch
  McBoardIn wired_in_;
  // The clocks of the walk quiet() found that skip() has still to do.
  static constexpr uint32_t kMaxWalk = 64;
  uint32_t walk_ = 0;
  // The walk's end as walk_clocks() found it: the register file, the
  // port's address in its last clock, whether that clock changed outputs.
  Regs walked_;
  uint8_t walked_raddr_ = 0;
  bool walked_changed_ = false;
  // What quiet() let move in the stretch: the walk's read port, the
  // running segment.
  typename Core::Let let_;
};

}  // namespace mc
