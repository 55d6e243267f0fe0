// mc_regs twin: the board's register file and command executor, clock by
// clock. Mirrors rtl/mc_regs.v, which documents how it works: the executor
// checks and applies the frames link_rx delivers and hands the reply to
// link_tx; the walker reads each sample's words after done, checks the
// following error and sends telemetry; the link counters are added to the
// shadow RAM by read-modify-write.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The registers are those of the RTL, same names, in R (the shadow RAM
// beside it); clock() is one edge and computes every next value from this
// clock's registers, as the RTL's nonblocking assignments do. Per-axis
// signals are bit masks (bit a for axis a) or arrays.
#pragma once

#include <cstdint>

#include "board_regs.hpp"

namespace mc {

template <int NAXES>
struct McRegsIn {
  bool operator==(const McRegsIn&) const = default;
  bool rst = false;
  // frames from link_rx
  bool frame = false;
  uint8_t seq = 0, cmd = 0, len = 0, pay_rdata = 0;
  bool crc_err = false, framing = false, junk = false;
  // link_tx
  bool tx_busy = false;
  // safety
  uint16_t fault = 0;
  bool armed = false, estop_act = false;
  uint8_t lim_act = 0;
  // motion_core
  bool pid_wready = false, pid_rready = false, pid_rvalid = false;
  uint32_t pid_rdata = 0;
  uint32_t seg_count = 0;
  bool ip_busy = false, ip_underrun = false, ip_ovf = false;
  uint16_t ip_seg_cnt = 0;
  uint8_t enc_err = 0;
  uint8_t enc_err_cnt[NAXES] = {};
  uint32_t enc_idx_pos[NAXES] = {};
  uint8_t enc_idx_armed = 0, enc_idx_seen = 0;
  uint8_t drv_en = 0;
  uint16_t drv_sel[NAXES] = {};
  bool done = false;
  uint32_t smp_rdata = 0;
  uint8_t pid_en = 0;
  // handwheel
  uint32_t hw_pos = 0;
  // the I/O blocks' live status (mc_io, mc_step)
  uint32_t io_stat = 0;
};

template <int NAXES = 3, int FIFO_AW = 9, int FILT_W = 8, int CLK_HZ = 12'000'000, int BAUD = 1'000'000,
          int STEPPERS = 0, bool SERVO = true, bool HANDWHEEL = true>
class McRegs {
  static_assert(NAXES >= 1 && NAXES <= 3, "mc_regs: NAXES must be 1..3");
  static_assert(FIFO_AW >= 6 && FIFO_AW <= 12, "mc_regs: FIFO_AW must be 6..12 (a frame of segments fits)");
  static_assert(FILT_W >= 1 && FILT_W <= 8, "mc_regs: FILT_W must be 1..8");

 public:
  bool operator==(const McRegs&) const = default;
  using In = McRegsIn<NAXES>;
  static constexpr uint8_t AXES = (1u << NAXES) - 1;
  static constexpr uint32_t WDOG_RESET = board::wdog_default(CLK_HZ) & 0xFFFFFF;
  static constexpr uint32_t DEPTH = 1u << FIFO_AW;

  // Executor states.
  enum : uint8_t {
    X_IDLE = 0,
    X_CHECK = 1,
    X_FETCH = 2,
    X_DECIDE = 3,
    X_APPLY = 4,
    X_PIDW = 5,
    X_PIDR = 6,
    X_PIDRW = 7,
    X_RD = 8,
    X_RD1 = 9,
    X_RD2 = 10,
    X_REPLY = 11,
    X_SET = 12
  };

  // The registers (widths in the comments where narrower than the type).
  struct R {
    bool operator==(const R&) const = default;
    // link drop counters: events not yet added
    bool drop_busy = false, cnt_nak_inc = false, cnt_dup_inc = false;
    uint8_t cnt_pend = 0;  // 5 bits
    bool cu1 = false, cu2 = false;
    uint8_t cu_c1 = 0, cu_c2 = 0;  // 3 bits
    // read path
    uint16_t ra = 0;
    uint8_t sa = 0;
    uint32_t q = 0, sq = 0;
    bool q_smp = false;
    uint16_t sample_cnt = 0;
    // executor
    uint16_t addr = 0;
    uint32_t data = 0;
    uint8_t xs = X_IDLE;  // 4 bits
    uint8_t f_seq = 0, f_cmd = 0, f_len = 0, status = 0;
    uint8_t bi = 0, rbi = 0;
    bool rv = false;
    uint8_t last_seq = 0;
    bool last_valid = false, last_full = false;
    bool seg_full = false;  // a segment frame's room check, decided as the frame is taken
    bool rep_pend = false, rep_sending = false, tlm_pend = false, tlm_sending = false;
    bool val_shadow = false, val_direct = false;
    uint8_t set_n = 0;               // 2 bits
    uint8_t set_t1 = 0, set_t2 = 0;  // 3 bits: {valid, axis}
    // strobes and settings
    bool arm_set_o = false, arm_clr_o = false;
    uint16_t fclr_o = 0;
    uint8_t safety_o = 0;
    uint32_t wdog_o = 0;  // 24 bits
    uint8_t ferr_o = 0;
    bool seg_wr_o = false, ip_abort_o = false, ip_hold_o = false, ip_clr_o = false;
    uint8_t enc_filt_o[NAXES] = {};  // FILT_W bits each
    uint8_t enc_dir_inv_o = 0, enc_idx_clr_en_o = 0;
    uint8_t enc_idx_arm_o = 0, enc_idx_disarm_o = 0, enc_err_clr_o = 0;
    uint8_t drv_ovr_o = 0, drv_ovr_we_o = 0;
    uint8_t hw_filt_o = 0;  // FILT_W bits
    bool hw_dir_inv_o = false;
    // walker and telemetry
    bool w_act = false, w_hdr = false, w_tlm = false, w_tlm_busy = false, w_end = false;
    uint8_t w_a = 0, w_k = 0, w_ptr = 0;  // 2, 3, 4 bits
    uint8_t done_d = 0;                   // 2 bits
    uint16_t tlm_left = 0, tlm_decim = 0;
    uint8_t tlm_axes = 0;  // 3 bits
    bool tlm_due_l = false;
    uint8_t t1 = 0, t2 = 0;    // 6 bits: {valid, last, hdr, k}
    uint8_t ta1 = 0, ta2 = 0;  // 2 bits
    uint8_t tlm_n = 0;         // 4 bits
    // sender
    uint8_t tlm_seq = 0;
    bool tx_start_o = false;
    uint8_t tx_seq_o = 0, tx_cmd_o = 0;
    bool tx_status_en_o = false;
    uint8_t tx_status_o = 0, tx_wbase_o = 0, tx_nwords_o = 0;
  };

  McRegs() {
    namespace br = board::reg;
    namespace bb = board::bits;
    shadow[sidx(br::WDOG)] = WDOG_RESET;
    shadow[sidx(br::SAFETY)] = bb::SAFETY_DEFAULT;
    shadow[sidx(br::ID)] = bb::ID_MAGIC | board::proto::VERSION;
    shadow[sidx(br::INFO)] =
        bb::info_word(NAXES, FIFO_AW, board::proto::VERSION, STEPPERS & ((1 << NAXES) - 1), SERVO, HANDWHEEL);
    shadow[sidx(br::CLK_HZ)] = uint32_t(CLK_HZ);
    shadow[sidx(br::BAUD)] = uint32_t(BAUD);
  }

  R r;
  uint32_t shadow[256] = {};

  // ---- outputs that are not registers ----------------------------------
  bool kick_o(const In& in) const { return in.frame; }
  uint8_t pay_raddr_o() const { return r.bi; }
  bool pid_we_o(bool rst) const { return r.xs == X_PIDW && !rst; }
  bool pid_re_o() const { return r.xs == X_PIDR; }
  uint8_t pid_addr_o() const { return uint8_t(r.addr); }  // pid_waddr_o and pid_raddr_o
  uint32_t data_o() const { return r.data; }              // seg_wdata, pid_wdata
  uint16_t drv_ovr_val_o() const { return uint16_t(r.data); }
  uint8_t ip_set_o() const { return (r.set_t2 & 4) ? uint8_t(1u << (r.set_t2 & 3) & 7) : uint8_t(0); }
  uint32_t ip_set_val_o() const { return r.sq; }
  // The I/O blocks' write bus: a global register write, in the apply clock.
  bool bus_we_o() const { return r.xs == X_APPLY && is_glb_a(r.addr); }
  uint8_t bus_addr_o() const { return uint8_t(r.addr & 0x1F); }
  uint8_t smp_raddr_o() const { return uint8_t((r.ra >> 4 & 3) << 3 | ra_fld(r.ra)); }
  bool tx_we_o() const { return w_wr() || x_wr(); }
  uint8_t tx_waddr_o() const { return w_wr() ? r.w_ptr : 0; }
  uint32_t tx_wdata_o(const In& in) const {
    if (w_wr() || !(r.val_direct || r.val_shadow)) return qv(in);
    return r.val_direct ? r.data : r.sq;
  }

  // ---- one clock edge ------------------------------------------------------
  // Returns false when the clock changed nothing.
  bool clock(const In& in) {
    namespace br = board::reg;
    namespace bb = board::bits;
    namespace bp = board::proto;
    if (quiet(in)) return false;  // a clock that changes nothing (the link idle), for a fraction of the work
    // Nonblocking: every right-hand side reads o, this clock's registers
    // (the helpers read r before the first write); the next values go
    // straight into r (n).
    const Pre p = pre(in);
    const R o = r;
    const uint32_t live_q = live(o.ra, in);
    R& n = r;

    // Decoding of the register address and the frame.
    const uint16_t addr = o.addr;
    const uint32_t data = o.data;
    const bool is_pid = (addr >> 8) == 0;
    const bool is_ax = is_ax_a(addr);
    const int a_ax = addr >> 4 & 3;
    const bool rep_busy = o.rep_pend || o.rep_sending;
    const bool dup = o.last_valid && o.f_seq == o.last_seq;
    const uint8_t chk = check(dup);
    const uint8_t filt = filt_len(data);
    const bool apply = o.xs == X_APPLY;
    const bool w_glb = p.w_glb;
    const bool w_ax = apply && is_ax && !is_pid;
    const bool rd_free = !o.w_act && !p.w_start;
    const bool xwr = x_wr();

    // Counter read-modify-write.
    const uint8_t cu_pick = p.cu_pick;
    const bool cu_go = p.cu_go;
    const uint8_t cnt_ev =
        uint8_t(uint32_t(in.junk) << 4 | uint32_t(o.cnt_dup_inc) << 3 | uint32_t(o.cnt_nak_inc) << 2 |
                uint32_t(in.framing || o.drop_busy) << 1 | uint32_t(in.crc_err));
    const uint16_t cu_half = uint16_t((o.cu_c2 & 1) ? o.sq >> 16 : o.sq);
    const uint16_t cu_inc = uint16_t(cu_half + (cu_half != 0xFFFF));
    const uint32_t cu_new =
        (o.cu_c2 & 1) ? (o.sq & 0xFFFF) | uint32_t(cu_inc) << 16 : (o.sq & 0xFFFF0000u) | cu_inc;

    // Shadow RAM: sq reads the word before this clock's write.
    read_path(o, live_q);
    if (!in.rst) {
      if (apply)
        shadow[sidx(addr)] = data;
      else if (o.cu2)
        shadow[cu_word(o.cu_c2 >> 1 & 3)] = cu_new;
    }
    if (in.rst) {
      n.cnt_pend = 0;
      n.cu1 = n.cu2 = false;
    } else {
      const uint32_t keep = o.cnt_pend & ~(uint32_t(cu_go) << cu_pick);
      const uint32_t again = uint32_t(o.cu2 && apply) << o.cu_c2;
      n.cnt_pend = uint8_t((keep | cnt_ev | again) & 0x1F);
      n.cu1 = cu_go;
      n.cu2 = o.cu1;
    }
    n.cu_c1 = cu_pick;
    n.cu_c2 = o.cu_c1;

    // Strobes and settings.
    n.arm_set_o = n.arm_clr_o = false;
    n.fclr_o = 0;
    n.ip_abort_o = n.ip_clr_o = false;
    n.enc_idx_arm_o = n.enc_idx_disarm_o = n.enc_err_clr_o = n.drv_ovr_we_o = 0;
    if (in.rst) {
      n.ip_hold_o = false;
      n.wdog_o = WDOG_RESET;
      n.safety_o = uint8_t(bb::SAFETY_DEFAULT);
      n.hw_filt_o = 0;
      n.hw_dir_inv_o = false;
      for (uint8_t& f : n.enc_filt_o) f = 0;
      n.enc_dir_inv_o = n.enc_idx_clr_en_o = n.drv_ovr_o = 0;
    } else {
      if (w_glb) {
        switch (addr & 0x1F) {
          case br::FAULT & 0x1F:
            n.fclr_o = uint16_t(data);
            n.enc_err_clr_o = uint8_t(data >> bb::F_ENC_LSB & AXES);
            break;
          case br::CTRL & 0x1F:
            n.arm_set_o = data >> bb::C_ARM & 1;
            n.arm_clr_o = !(data >> bb::C_ARM & 1);
            n.ip_hold_o = data >> bb::C_IP_HOLD & 1;
            break;
          case br::WDOG & 0x1F:
            n.wdog_o = data & 0xFFFFFF;
            break;
          case br::SAFETY & 0x1F:
            n.safety_o = uint8_t(data);
            break;
          case br::IP_CTRL & 0x1F:
            n.ip_abort_o = data >> bb::I_ABORT & 1;
            n.ip_clr_o = data >> bb::I_CLR & 1;
            break;
          case br::HW_CFG & 0x1F:
            n.hw_filt_o = filt;
            n.hw_dir_inv_o = data >> bb::E_DIR_INV & 1;
            break;
          default:
            break;
        }
      }
      if (w_ax) {
        const uint8_t m = uint8_t(1u << a_ax);
        switch (addr & 0xF) {
          case br::AX_ENC_CFG:
            n.enc_filt_o[a_ax] = filt;
            n.enc_dir_inv_o = set_bit(n.enc_dir_inv_o, m, data >> bb::E_DIR_INV & 1);
            n.enc_idx_clr_en_o = set_bit(n.enc_idx_clr_en_o, m, data >> bb::E_IDX_CLR_EN & 1);
            break;
          case br::AX_IDX:
            n.enc_idx_arm_o = set_bit(0, m, data >> bb::X_ARM & 1);
            n.enc_idx_disarm_o = set_bit(0, m, data >> bb::X_DISARM & 1);
            break;
          case br::AX_ENC_STAT:
            n.enc_err_clr_o = set_bit(0, m, data >> bb::ES_W_ERR_CLR & 1);
            break;
          case br::AX_DRV:
            n.drv_ovr_we_o = set_bit(0, m, data >> bb::D_OVR & 1);
            n.drv_ovr_o = set_bit(n.drv_ovr_o, m, data >> bb::D_OVR & 1);
            break;
          default:
            break;
        }
      }
    }

    // The executor.
    n.drop_busy = n.cnt_nak_inc = n.cnt_dup_inc = false;
    n.seg_wr_o = false;
    n.rv = false;
    if (in.rst) {
      n.xs = X_IDLE;
      n.last_valid = false;
      n.last_full = false;
      n.rep_pend = false;
    } else {
      if (in.frame && (o.xs != X_IDLE || rep_busy)) n.drop_busy = true;
      if (o.rv) {
        if (o.f_cmd != bp::CMD_SEG && o.rbi < 2)
          n.addr = uint16_t(in.pay_rdata << 8 | addr >> 8);
        else
          n.data = uint32_t(in.pay_rdata) << 24 | data >> 8;
        n.seg_wr_o = o.f_cmd == bp::CMD_SEG && (o.rbi & 3) == 3;
      }
      if (o.tx_start_o && o.tx_status_en_o) n.rep_pend = false;
      switch (o.xs) {
        case X_IDLE:
          if (in.frame && !rep_busy) {
            n.f_seq = in.seq;
            n.f_cmd = in.cmd;
            n.f_len = in.len;
            n.seg_full = (uint32_t(in.len) >> 2) + (in.seg_count & (2 * DEPTH - 1)) > DEPTH;
            n.xs = X_CHECK;
          }
          break;
        case X_CHECK:
          n.status = chk;
          n.bi = 0;
          n.val_direct = false;
          n.val_shadow = false;
          if (o.f_cmd == bp::CMD_PING) {  // answered with ID, from the shadow RAM
            n.last_valid = false;
            n.addr = br::ID;
            n.val_shadow = true;
          } else if (o.f_cmd == bp::CMD_SEG) {
            n.addr = br::IP_STAT;
          }
          if (chk == bp::ST_BAD_LEN || chk == bp::ST_BAD_CMD || chk == bp::ST_FULL) {
            if (chk == bp::ST_FULL) {  // its copies get FULL too, never a later evaluation
              n.last_seq = o.f_seq;
              n.last_valid = true;
              n.last_full = true;
            }
            n.cnt_nak_inc = true;
            n.val_direct = true;
            n.data = 0;
            n.xs = X_REPLY;
          } else if (chk == bp::ST_DUP) {  // a repeated segment frame
            n.cnt_dup_inc = true;
            n.xs = X_RD;
          } else if (o.f_len == 0) {
            n.xs = X_RD;
          } else {
            n.xs = X_FETCH;
          }
          break;
        case X_FETCH:
          if (o.bi != o.f_len) {
            n.bi = uint8_t(o.bi + 1);
            n.rv = true;
            n.rbi = o.bi;
          } else if (!o.rv && !o.seg_wr_o) {
            n.xs = X_DECIDE;
          }
          break;
        case X_DECIDE:
          if (o.f_cmd == bp::CMD_SEG) {
            n.last_seq = o.f_seq;
            n.last_valid = true;
            n.last_full = false;
            n.xs = X_RD;
          } else if (o.f_cmd == bp::CMD_READ ? !rd_ok(addr) : !wr_ok(addr)) {
            n.status = bp::ST_BAD_REG;
            n.cnt_nak_inc = true;
            n.val_direct = true;
            n.data = 0;
            n.xs = X_REPLY;
          } else {
            if (dup) {
              n.status = bp::ST_DUP;
              n.cnt_dup_inc = true;
            } else {
              n.last_seq = o.f_seq;
              n.last_valid = true;
              n.last_full = false;
            }
            if (o.f_cmd == bp::CMD_WRITE) {
              n.val_direct = true;
              n.xs = dup ? X_REPLY : (is_pid ? X_PIDW : X_APPLY);
            } else {
              n.val_shadow = !is_pid && rd_shadow(addr);
              n.xs = is_pid ? X_PIDR : X_RD;
            }
          }
          break;
        case X_APPLY:
          // IP_CTRL.set: the positions wait in the shadow RAM; X_SET reads
          // them in turn and each strobes its axis as it arrives.
          if (w_glb && (addr & 0x1F) == (br::IP_CTRL & 0x1F) && (data >> bb::I_SET & 1)) {
            n.addr = br::IP_SET_X;
            n.set_n = 0;
            n.xs = X_SET;
          } else {
            n.xs = X_REPLY;
          }
          break;
        case X_SET:
          if (rd_free) {
            n.addr = uint16_t(addr + 1);
            n.set_n = uint8_t((o.set_n + 1) & 3);
            if (o.set_n == 2) n.xs = X_REPLY;
          }
          break;
        case X_PIDW:
          if (in.pid_wready) n.xs = X_REPLY;
          break;
        case X_PIDR:
          if (in.pid_rready) n.xs = X_PIDRW;
          break;
        case X_PIDRW:
          if (in.pid_rvalid) {
            n.val_direct = true;
            n.data = in.pid_rdata;
            n.xs = X_REPLY;
          }
          break;
        case X_RD:
          if (rd_free) n.xs = X_RD1;
          break;
        case X_RD1:
          n.xs = X_RD2;
          break;
        default:  // X_RD2, X_REPLY: the value goes into word 0 of link_tx's RAM
          if (xwr) {
            n.rep_pend = true;
            n.xs = X_IDLE;
          }
          break;
      }
    }
    if (in.rst) {
      n.set_t1 = n.set_t2 = 0;
    } else {
      n.set_t1 = uint8_t(uint32_t(o.xs == X_SET && rd_free) << 2 | o.set_n);
      n.set_t2 = o.set_t1;
    }

    clock_tail(o, in, p);
    return true;
  }

  // clock() of a walk with nothing else under way (quiet_but_walk(in)) and
  // no telemetry to send (walk_silent()): of the clock only the read path
  // and the walker's part move (the delay line from done, the walker and
  // its pipelines, the following-error check); the executor, the TLM
  // register, the sample count and the sender hold as clock() would leave
  // them, for want of a frame, a write, done, a telemetry word or a reply.
  // A fraction of clock()'s work: McBoard::walk_clocks clocks a whole walk
  // on a copy each sample. Returns what clock() would.
  bool walk_clock(const In& in) {
    if (walk_settled(in)) return false;  // quiet(in): clock() changes nothing
    R& n = r;
    const bool w_start = r.done_d >> 1 & 1, w_end = r.w_end;
    const bool t_v = r.t2 >> 5 & 1, t_last = r.t2 >> 4 & 1, t_check = t_v && t_follow_();
    const uint8_t ta2 = r.ta2;
    const uint32_t q_v = qv(in), sq = r.sq;
    const uint16_t ra = r.ra;
    const Walker w{r.w_act, r.w_hdr, walk_last(), r.w_a, r.w_k, r.t1, r.ta1};
    n.sq = shadow[r.sa];
    n.q = live(ra, in);
    n.q_smp = ra_smp(ra);
    n.done_d = uint8_t(r.done_d << 1 & 3);
    walk(w, false, w_start, false, r.addr, sidx(r.addr));  // no telemetry due (walk_silent)
    if (w_start) {
      n.w_ptr = 1;
      n.w_tlm_busy = false;
    }
    if (w_end) n.w_tlm_busy = false;
    n.w_end = t_v && t_last;
    n.ferr_o = t_check ? uint8_t(uint32_t(ferr_trip(q_v, sq)) << ta2 & AXES) : uint8_t(0);
    return true;
  }

  // ---- fast-forward --------------------------------------------------------
  // A clock with these inputs changes no register nor the shadow RAM: the
  // executor idle, no frame to hand to link_tx (none waiting, or link_tx
  // busy with one), no counter pending, the walker and every pipeline
  // settled, no strobe. The register file has no free-running counter, so
  // any number of such clocks changes nothing.
  bool quiet(const In& in) const { return quiet_but_walk(in) && walk_settled(in); }
  // Everything of quiet() but the walker and the read pipeline it drives
  // (the board's fast-forward runs a walk without telemetry on its own:
  // McBoard::walk_clocks).
  bool quiet_but_walk(const In& in) const {
    if (in.rst || in.frame || in.crc_err || in.framing || in.junk || in.done) return false;
    if (r.xs != X_IDLE || r.tx_start_o) return false;
    if (!in.tx_busy && (r.rep_pend || r.rep_sending || r.tlm_pend || r.tlm_sending)) return false;
    if (r.drop_busy || r.cnt_nak_inc || r.cnt_dup_inc || r.cnt_pend != 0 || r.cu1 || r.cu2 || r.cu_c1 != 4 ||
        r.cu_c2 != 4)
      return false;
    if (r.rv || r.seg_wr_o || r.arm_set_o || r.arm_clr_o || r.fclr_o != 0 || r.ip_abort_o || r.ip_clr_o ||
        r.enc_idx_arm_o != 0 || r.enc_idx_disarm_o != 0 || r.enc_err_clr_o != 0 || r.drv_ovr_we_o != 0 ||
        r.ferr_o != 0)
      return false;
    return r.set_t1 == r.set_n && r.set_t2 == r.set_n;
  }
  // The walker idle and the read pipeline settled on the register address.
  bool walk_settled(const In& in) const {
    if (r.w_act || r.done_d != 0 || r.w_end || r.w_tlm_busy) return false;
    const uint8_t t = uint8_t(uint32_t(walk_last()) << 4 | uint32_t(r.w_hdr) << 3 | r.w_k);
    if (r.t1 != t || r.t2 != t || r.ta1 != r.w_a || r.ta2 != r.w_a) return false;
    return r.ra == r.addr && r.sa == sidx(r.addr) && r.q == live(r.addr, in) && r.q_smp == ra_smp(r.addr) &&
           r.sq == shadow[r.sa];
  }

  // The read pipeline follows an axis's drive command: the register being
  // read, or the one addressed, is an AX_DRV.
  bool reads_drive() const { return is_drv(r.addr) || is_drv(r.ra); }
  static constexpr bool is_drv(uint16_t a) { return (a >> 9 & 1) && (a & 0xF) == board::reg::AX_DRV; }

  // This walk sends no telemetry: none due for the sample it will read,
  // and none being written. (McBoard::walk_clocks would find that too, on a
  // copy of the register file; this refuses it before the copy.)
  bool walk_silent() const { return !r.w_tlm && !r.w_tlm_busy && !(r.done_d != 0 && r.tlm_due_l); }

  // ---- combinational helpers (the RTL's wires) ---------------------------
  // Shadow RAM index of a register address: {per-axis, low seven bits}.
  static constexpr uint8_t sidx(uint16_t a) { return uint8_t((a >> 9 & 1) << 7 | (a & 0x7F)); }
  // A link counter's word: LINK_CRC + w.
  static constexpr uint8_t cu_word(uint32_t w) { return sidx(uint16_t(board::reg::LINK_CRC + w)); }

 private:
  static constexpr uint32_t CNT_SHADOW =
      1u << (board::reg::LINK_CRC & 0x1F) | 1u << (board::reg::LINK_CMD & 0x1F) |
      1u << (board::reg::LINK_JUNK & 0x1F) | 1u << (board::reg::ID & 0x1F) | 1u << (board::reg::INFO & 0x1F) |
      1u << (board::reg::CLK_HZ & 0x1F) | 1u << (board::reg::BAUD & 0x1F);

  // Bit i: the global register i (the axis register at offset i) takes
  // writes, or reads back from the shadow RAM what was written: the table's
  // access, as rtl/board_regs.vh's R_GLOBAL_WMASK .. R_AX_SHADOW.
  static constexpr uint32_t reg_mask(bool per_axis, bool shadow) {
    uint32_t m = 0;
    for (const board::RegDef& d : board::REGS)
      if (d.per_axis == per_axis && (shadow ? d.access == board::Access::RW : d.access != board::Access::R))
        m |= 1u << (d.addr & 0x1F);
    return m;
  }
  static constexpr uint32_t GLOBAL_WMASK = reg_mask(false, false), GLOBAL_SHADOW = reg_mask(false, true);
  static constexpr uint32_t AX_WMASK = reg_mask(true, false), AX_SHADOW = reg_mask(true, true);

  // What the parts of a clock read besides the registers before it (o):
  // the helpers' values, which read r, so before the clock's first write.
  struct Pre {
    bool w_glb, w_start, tlm_due, tlm_free, w_last, t_v, t_last, t_follow, wwr, cu_go;
    uint8_t cu_pick;
    uint32_t q_v;
  };
  Pre pre(const In& in) const {
    Pre p{};
    p.w_glb = r.xs == X_APPLY && is_glb_a(r.addr);
    p.w_start = r.done_d >> 1 & 1;
    p.tlm_due = r.tlm_decim != 0 && (r.tlm_left >> 1) == 0;
    p.tlm_free = !(r.tlm_pend || r.tlm_sending || r.w_tlm_busy);
    p.w_last = walk_last();
    p.t_v = r.t2 >> 5 & 1;
    p.t_last = r.t2 >> 4 & 1;
    p.t_follow = t_follow_();
    p.wwr = w_wr();
    p.q_v = qv(in);
    const bool cu_free = !r.w_act && r.xs != X_RD && r.xs != X_SET && !r.cu1 && !r.cu2;
    p.cu_pick = pick(r.cnt_pend);
    p.cu_go = cu_free && r.cnt_pend != 0;
    return p;
  }
  // The walker's registers a clock reads (before its edge; last: walk_last()).
  struct Walker {
    bool act, hdr, last;
    uint8_t a, k, t1, ta1;
  };
  // The walker's part of a clock, from its registers o: a walk starts
  // (tlm: it writes telemetry) or steps to its next word; the read address
  // follows it, else the register address (the shadow RAM then at
  // idle_sa); the word's valid, last, header and index, and its axis,
  // follow two clocks behind. Inlined: walk_clock() runs it some twenty
  // times a sample, where a call showed in the board's instruction count.
  [[gnu::always_inline]] void walk(const Walker& o, bool rst, bool start, bool tlm, uint16_t addr,
                                   uint8_t idle_sa) {
    namespace br = board::reg;
    R& n = r;
    if (rst) {
      n.w_act = false;
    } else if (start) {
      n.w_act = true;
      n.w_hdr = true;
      n.w_a = 0;
      n.w_k = 0;
      n.w_tlm = tlm;
    } else if (o.act) {
      n.w_hdr = false;
      if (o.last) n.w_act = false;
      if (!o.hdr) {
        n.w_k = o.k == 4 ? 0 : uint8_t(o.k + 1);
        if (o.k == 4) n.w_a = uint8_t((o.a + 1) & 3);
      }
    }
    if (o.act) {
      n.ra = o.hdr ? br::TLM_HDR : uint16_t(br::AXIS_BASE | o.a << 4 | w_off(o.k));
      n.sa = uint8_t(0x80 | o.a << 4 | br::AX_FERR);  // sidx(AXIS_BASE | w_a << 4 | AX_FERR)
    } else {
      n.ra = addr;
      n.sa = idle_sa;
    }
    if (rst) {
      n.t1 = n.t2 = 0;
    } else {
      n.t1 = uint8_t(uint32_t(o.act) << 5 | uint32_t(o.last) << 4 | uint32_t(o.hdr) << 3 | o.k);
      n.t2 = o.t1;
    }
    n.ta1 = o.a;
    n.ta2 = o.ta1;
  }
  // The read path: the shadow word (before this clock's write), the live
  // value of o.ra (live_q, read before the first write).
  void read_path(const R& o, uint32_t live_q) {
    r.sq = shadow[o.sa];
    r.q = live_q;
    r.q_smp = ra_smp(o.ra);
  }
  // The parts of a clock after the executor: the TLM register, the sample
  // count, the walker and the read address, the telemetry words and the
  // following-error check, the sender.
  void clock_tail(const R& o, const In& in, const Pre& p) {
    namespace br = board::reg;
    namespace bb = board::bits;
    namespace bp = board::proto;
    R& n = r;
    const uint16_t addr = o.addr;
    const uint32_t data = o.data;
    const bool w_glb = p.w_glb, w_start = p.w_start, tlm_due = p.tlm_due, tlm_free = p.tlm_free,
               w_last = p.w_last, t_v = p.t_v, t_last = p.t_last, t_follow = p.t_follow, wwr = p.wwr,
               cu_go = p.cu_go;
    const uint8_t cu_pick = p.cu_pick;
    const uint32_t q_v = p.q_v;
    // TLM register: a write restarts the decimation.
    if (in.rst) {
      n.tlm_decim = 0;
      n.tlm_axes = 0;
      n.tlm_left = 0;
    } else if (w_glb && (addr & 0x1F) == (br::TLM & 0x1F)) {
      n.tlm_decim = uint16_t(data >> bb::T_DECIM_LSB);
      n.tlm_axes = uint8_t(data >> bb::T_AXES_LSB & 7);
      n.tlm_left = uint16_t(data >> bb::T_DECIM_LSB);
    } else if (in.done) {
      n.tlm_left = (o.tlm_decim == 0 || tlm_due) ? o.tlm_decim : uint16_t(o.tlm_left - 1);
    }

    // Sample count and decimation.
    n.done_d = uint8_t((o.done_d << 1 | uint32_t(in.done)) & 3);
    if (in.done) n.tlm_due_l = tlm_due;
    if (in.rst) {
      n.done_d = 0;
      n.sample_cnt = 0;
    } else if (in.done) {
      n.sample_cnt = uint16_t(o.sample_cnt + 1);
    }

    // The walker.
    walk(Walker{o.w_act, o.w_hdr, w_last, o.w_a, o.w_k, o.t1, o.ta1}, in.rst, w_start,
         o.tlm_due_l && tlm_free, addr, cu_go ? cu_word(cu_pick >> 1) : sidx(addr));

    // Telemetry words and the following-error check, as the values arrive.
    n.ferr_o = 0;
    n.w_end = t_v && t_last;
    if (in.rst) {
      n.w_tlm_busy = false;
    } else {
      if (w_start) {
        n.w_ptr = 1;
        n.w_tlm_busy = o.tlm_due_l && tlm_free;
      }
      if (wwr) n.w_ptr = uint8_t((o.w_ptr + 1) & 0xF);
      if (o.w_end) {
        n.w_tlm_busy = false;
        // Only a walk that wrote telemetry: its frame may still wait behind
        // a reply when the next sample's walk ends (Ts under a reply's time).
        if (o.w_tlm_busy) n.tlm_n = uint8_t((o.w_ptr - 1) & 0xF);
      }
      if (t_v && t_follow) n.ferr_o = uint8_t(uint32_t(ferr_trip(q_v, o.sq)) << o.ta2 & AXES);
    }

    // Sender arbitration: the reply first, then telemetry.
    n.tx_start_o = false;
    if (in.rst) {
      n.tlm_pend = n.tlm_sending = n.rep_sending = false;
      n.tlm_seq = 0;
    } else {
      if (o.w_end && o.w_tlm_busy) n.tlm_pend = true;
      if (!in.tx_busy && !o.tx_start_o) {
        n.rep_sending = false;
        n.tlm_sending = false;
        if (o.rep_pend) {
          n.tx_start_o = true;
          n.tx_seq_o = o.f_seq;
          n.tx_cmd_o = uint8_t(o.f_cmd | bp::REPLY);
          n.tx_status_en_o = true;
          n.tx_status_o = o.status;
          n.tx_wbase_o = 0;
          n.tx_nwords_o = 1;
          n.rep_sending = true;
        } else if (o.tlm_pend) {
          n.tx_start_o = true;
          n.tx_seq_o = o.tlm_seq;
          n.tx_cmd_o = bp::CMD_TLM;
          n.tx_status_en_o = false;
          n.tx_wbase_o = 1;
          n.tx_nwords_o = o.tlm_n;
          n.tlm_seq = uint8_t(o.tlm_seq + 1);
          n.tlm_pend = false;
          n.tlm_sending = true;
        }
      }
    }
  }

  static uint8_t set_bit(uint8_t v, uint8_t m, bool b) { return b ? uint8_t(v | m) : uint8_t(v & ~m); }
  static uint8_t pick(uint8_t pend) {
    for (uint8_t c = 0; c < 4; ++c)
      if (pend >> c & 1) return c;
    return 4;
  }
  static uint8_t w_off(uint8_t k) {
    namespace br = board::reg;
    switch (k) {
      case 0:
        return br::AX_POS;  // the TLM_AXIS_WORDS order
      case 1:
        return br::AX_CMD;
      case 2:
        return br::AX_ERR;
      case 3:
        return br::AX_OUT;
      default:
        return br::AX_FOLLOW;
    }
  }
  // The sample RAM field of a per-axis register, 7 for none.
  static uint8_t ra_fld(uint16_t ra) {
    namespace br = board::reg;
    switch (ra & 0xF) {
      case br::AX_CMD:
        return 0;
      case br::AX_POS:
        return 1;
      case br::AX_ERR:
        return 2;
      case br::AX_OUT:
        return 3;
      case br::AX_FOLLOW:
        return 4;
      default:
        return 7;
    }
  }
  static bool ra_smp(uint16_t ra) { return (ra >> 9 & 1) && ra_fld(ra) != 7; }

  static bool is_glb_a(uint16_t a) {
    return (a >> 8) == (board::reg::ID >> 8) && (a & 0xFF) < (board::reg::GLOBAL_END & 0xFF);
  }
  static bool is_ax_a(uint16_t a) {
    return (a >> 8) == (board::reg::AXIS_BASE >> 8) && (a >> 6 & 3) == 0 && (a >> 4 & 3) < NAXES &&
           (a & 0xF) < board::reg::AX_END;
  }
  static bool rd_ok(uint16_t a) {
    const uint32_t p_ax = a >> 4 & 0xF, p_rg = a & 0xF;
    if ((a >> 8) == 0) return (p_ax < NAXES && (p_rg < 10 || p_rg == 0xF)) || (p_ax == 0xF && p_rg <= 2);
    return is_glb_a(a) || is_ax_a(a);
  }
  static bool wr_ok(uint16_t a) {
    const uint32_t p_ax = a >> 4 & 0xF, p_rg = a & 0xF;
    if ((a >> 8) == 0) return (p_ax < NAXES && (p_rg < 10 || p_rg == 0xF)) || (p_ax == 0xF && p_rg == 0);
    if (is_glb_a(a)) return GLOBAL_WMASK >> (a & 0x1F) & 1;
    return is_ax_a(a) && (AX_WMASK >> (a & 0xF) & 1);
  }
  static bool rd_shadow(uint16_t a) {
    if (is_glb_a(a)) return (GLOBAL_SHADOW | CNT_SHADOW) >> (a & 0x1F) & 1;
    return AX_SHADOW >> (a & 0xF) & 1;
  }
  // The filter-length field, clamped to the longest filter FILT_W bits hold.
  static uint8_t filt_len(uint32_t data) {
    const uint32_t f = data >> board::bits::E_FILT_LSB & 0xFF;
    return uint8_t((f >> FILT_W) != 0 ? (1u << FILT_W) - 1 : f);
  }

  // The checks of a frame that need no payload.
  uint8_t check(bool dup) const {
    namespace bp = board::proto;
    switch (r.f_cmd) {
      case bp::CMD_PING:
        return r.f_len != 0 ? bp::ST_BAD_LEN : bp::ST_OK;
      case bp::CMD_READ:
        return r.f_len != 2 ? bp::ST_BAD_LEN : bp::ST_OK;
      case bp::CMD_WRITE:
        return r.f_len != 6 ? bp::ST_BAD_LEN : bp::ST_OK;
      case bp::CMD_SEG: {
        const bool len_ok = r.f_len != 0 && r.f_len % bp::SEG_BYTES == 0 && r.f_len <= bp::MAX_LEN;
        if (!len_ok) return bp::ST_BAD_LEN;
        if (dup) return r.last_full ? bp::ST_FULL : bp::ST_DUP;
        return r.seg_full ? bp::ST_FULL : bp::ST_OK;
      }
      default:
        return bp::ST_BAD_CMD;
    }
  }

  // The live-value multiplexer (registered into q).
  uint32_t live(uint16_t ra, const In& in) const {
    namespace br = board::reg;
    namespace bb = board::bits;
    const int ax = ra >> 4 & 3;
    if (ra >> 9 & 1) {
      if (ax >= NAXES) return 0;  // the RTL pads absent axes with zeros
      switch (ra & 0xF) {
        case br::AX_IDX:
          return in.enc_idx_pos[ax];
        case br::AX_ENC_STAT:
          return uint32_t(in.enc_idx_seen >> ax & 1) << bb::ES_IDX_SEEN |
                 uint32_t(in.enc_idx_armed >> ax & 1) << bb::ES_IDX_ARMED |
                 uint32_t(in.enc_err >> ax & 1) << bb::ES_ERR | in.enc_err_cnt[ax];
        case br::AX_OUT:
          return uint32_t(in.drv_en >> ax & 1) << bb::O_DRV_EN;
        case br::AX_DRV:
          return uint32_t(r.drv_ovr_o >> ax & 1) << bb::D_OVR | in.drv_sel[ax];
        default:
          return 0;
      }
    }
    switch (ra & 0x1F) {
      case br::STATUS & 0x1F:
        return uint32_t(in.armed) << bb::ST_ARMED | uint32_t(in.estop_act) << bb::ST_ESTOP_IN |
               uint32_t(in.ip_busy) << bb::ST_IP_BUSY | uint32_t(in.ip_underrun) << bb::ST_IP_UNDERRUN |
               uint32_t(in.ip_ovf) << bb::ST_IP_OVF | uint32_t(in.lim_act & AXES) << bb::ST_LIMIT_IN_LSB |
               uint32_t(in.drv_en & AXES) << bb::ST_DRV_EN_LSB |
               uint32_t(in.pid_en & AXES) << bb::ST_PID_EN_LSB;
      case br::FAULT & 0x1F:
        return in.fault;
      case br::IP_STAT & 0x1F:
        return (in.seg_count & (2 * DEPTH - 1)) << bb::IS_COUNT_LSB | uint32_t(in.ip_busy) << bb::IS_BUSY |
               uint32_t(in.ip_underrun) << bb::IS_UNDERRUN | uint32_t(in.ip_ovf) << bb::IS_OVF;
      case br::IP_SEGS & 0x1F:
        return in.ip_seg_cnt;
      case br::HW_POS & 0x1F:
        return in.hw_pos;
      case br::TLM_HDR & 0x1F:
        return uint32_t(in.fault) << 16 | r.sample_cnt;
      case br::IO_STAT & 0x1F:
        return in.io_stat;
      default:
        return 0;
    }
  }
  // The read path's value: the multiplexer's, ORed with the sample RAM's.
  uint32_t qv(const In& in) const { return r.q_smp ? (in.smp_rdata | r.q) : r.q; }

  bool walk_last() const { return !r.w_hdr && r.w_k == 4 && r.w_a == NAXES - 1; }
  bool t_follow_() const { return !(r.t2 >> 3 & 1) && (r.t2 & 7) == 4; }  // checked, not sent
  // The walker writes a telemetry word into link_tx's RAM this clock.
  bool w_wr() const {
    const bool t_v = r.t2 >> 5 & 1, t_hdr = r.t2 >> 3 & 1;
    return t_v && r.w_tlm && (t_hdr || ((r.tlm_axes >> r.ta2 & 1) && !t_follow_()));
  }
  // The reply's value goes into word 0 this clock.
  bool x_wr() const { return r.xs == X_RD2 || (r.xs == X_REPLY && !w_wr()); }
  // |FOLLOW| > FERR with FERR != 0 (FERR: the low half of the shadow word).
  static bool ferr_trip(uint32_t follow, uint32_t ferr_word) {
    const int64_t lim = ferr_word & 0xFFFF;
    const int64_t d = int32_t(follow);
    return lim != 0 && (d < 0 ? d + lim < 0 : d > lim);
  }
};

}  // namespace mc
