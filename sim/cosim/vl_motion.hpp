// Port mapping between a Verilated rtl/motion_core.v and the twin's
// MotionIn/MotionOut (hls/motion_core.hpp), for any NAXES. Used by the
// co-simulation's RtlCore and by the C/RTL test.
#pragma once

#include <cstdint>

#include "hls/motion_core.hpp"
#include "sim/cosim/vl_ports.hpp"

namespace mc::sim {

// Present the inputs of one clock to the model (clk untouched).
template <int N, typename Model>
void apply_inputs(Model& d, const MotionIn<N>& in) {
  d.rst = in.rst;
  d.pid_we = in.pid_we;
  d.pid_waddr = in.pid_waddr;
  d.pid_wdata = in.pid_wdata;
  d.pid_re = in.pid_re;
  d.pid_raddr = in.pid_raddr;
  d.seg_wr = in.seg_wr;
  d.seg_wdata = in.seg_wdata;
  d.ip_abort = in.ip_abort;
  d.ip_hold = in.ip_hold;
  d.ip_clr = in.ip_clr;
  d.ip_set = in.ip_set;
  for (int a = 0; a < 3; ++a) vl::put32(d.ip_set_pos, a, uint32_t(in.ip_set_pos[a]));
  d.ip_jog = in.ip_jog;
  d.ip_jog_neg = in.ip_jog_neg;
  uint32_t ea = 0, eb = 0, ez = 0, elat = 0, dinv = 0, iclr = 0, arm = 0, dis = 0, eclr = 0, allow = 0,
           ovr = 0, ovw = 0;
  uint64_t filt = 0;
  for (int a = 0; a < N; ++a) {
    ea |= uint32_t(in.enc_a[a]) << a;
    eb |= uint32_t(in.enc_b[a]) << a;
    ez |= uint32_t(in.enc_z[a]) << a;
    elat |= uint32_t(in.enc_latch[a]) << a;
    filt |= uint64_t(in.enc_filt[a] & 0xFF) << (8 * a);
    dinv |= uint32_t(in.enc_dir_inv[a]) << a;
    iclr |= uint32_t(in.enc_idx_clr_en[a]) << a;
    arm |= uint32_t(in.enc_idx_arm[a]) << a;
    dis |= uint32_t(in.enc_idx_disarm[a]) << a;
    eclr |= uint32_t(in.enc_err_clr[a]) << a;
    allow |= uint32_t(in.drv_allow[a]) << a;
    ovr |= uint32_t(in.drv_ovr[a]) << a;
    ovw |= uint32_t(in.drv_ovr_we[a]) << a;
  }
  vl::set(d.enc_a, ea);
  vl::set(d.enc_b, eb);
  vl::set(d.enc_z, ez);
  vl::set(d.enc_latch, elat);
  vl::set(d.enc_filt, filt);
  vl::set(d.enc_dir_inv, dinv);
  vl::set(d.enc_idx_clr_en, iclr);
  vl::set(d.enc_idx_arm, arm);
  vl::set(d.enc_idx_disarm, dis);
  vl::set(d.enc_err_clr, eclr);
  vl::set(d.drv_allow, allow);
  vl::set(d.drv_ovr, ovr);
  vl::set(d.drv_ovr_we, ovw);
  d.drv_ovr_val = uint16_t(in.drv_ovr_val);
  d.smp_raddr = in.smp_raddr;
}

// The model's outputs in the current clock (after eval with these inputs).
template <int N, typename Model>
MotionOut<N> read_outputs(const Model& d) {
  MotionOut<N> o;
  o.pid_wready = d.pid_wready;
  o.pid_rready = d.pid_rready;
  o.pid_rvalid = d.pid_rvalid;
  o.pid_rdata = d.pid_rdata;
  o.seg_count = int(d.seg_count);
  o.ip_busy = d.ip_busy;
  o.ip_underrun = d.ip_underrun;
  o.ip_ovf = d.ip_ovf;
  o.ip_seg_cnt = int(d.ip_seg_cnt);
  o.tick = d.tick;
  o.done = d.done;
  o.smp_rdata = d.smp_rdata;
  for (int a = 0; a < N; ++a) {
    o.pwm[a] = (d.pwm_o >> a) & 1;
    o.dir[a] = (d.dir_o >> a) & 1;
    o.drv_en[a] = (d.drv_en_o >> a) & 1;
    o.drv_u[a] = int16_t(vl::get_bits(d.drv_u, 16 * a, 16));
    o.drv_cmd[a] = int16_t(vl::get_bits(d.drv_cmd, 16 * a, 16));
    o.smp_sat[a] = (d.smp_sat >> a) & 1;
    o.pid_en[a] = (d.pid_en >> a) & 1;
    o.pos[a] = int32_t(vl::get_bits(d.pos, 32 * a, 32));
    o.cmd[a] = int32_t(vl::get_bits(d.cmd, 32 * a, 32));
    QuadOut& e = o.enc[a];
    e.pos = o.pos[a];
    e.err = (d.enc_err >> a) & 1;
    e.err_cnt = vl::get_bits(d.enc_err_cnt, 8 * a, 8);
    e.idx_pos = int32_t(vl::get_bits(d.enc_idx_pos, 32 * a, 32));
    e.idx_armed = (d.enc_idx_armed >> a) & 1;
    e.idx_seen = (d.enc_idx_seen >> a) & 1;
    e.vel = int32_t(vl::get_bits(d.enc_vel, 32 * a, 32));
  }
  return o;
}

}  // namespace mc::sim
