// C/RTL co-simulation of motion_core: the Verilated RTL and the hls twin
// (hls/motion_core.hpp) get the same inputs every clock and every output is
// compared every clock. The sub-blocks have their own bit-exact tests; this
// one is about the composition: sample timing, the telemetry latch, the drive
// stage and the configuration handshake. A small integer motor model in the
// testbench closes the loops, so the decoders see motion the PID caused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <random>
#include <sstream>

#include "Vmotion_core.h"
#include "Vmotion_core2.h"
#include "hls/motion_core.hpp"
#include "interp_bench.hpp"
#include "sim/cosim/vl_motion.hpp"
#include "sim/plant/dc_motor.hpp"
#include "vl_context.hpp"

namespace mc::test {
namespace {

template <typename Model, int N>
class MotionCosim {
 public:
  using Twin = MotionCore<N>;
  explicit MotionCosim(uint32_t seed) : rng_(seed), ctx_(random_context(seed)) {
    dut_ = std::make_unique<Model>(ctx_.get(), "motion_core");
    in_.rst = true;
    for (int i = 0; i < 4; ++i) cycle();
    in_.rst = false;
  }
  ~MotionCosim() { dut_->final(); }

  typename Twin::In in_;
  std::mt19937_64 rng_;
  uint64_t cycles_ = 0;
  int64_t count_[N] = {};  // the testbench motor's encoder counts
  int32_t vel_[N] = {};    // its speed, counts per 2^12 clocks

  // One clock: present in_ to both, compare outputs, then the edge.
  void cycle() {
    drive_inputs();
    dut_->clk = 0;
    dut_->eval();
    const typename Twin::Out t = twin_.outputs(in_.pid_we);
    compare(t);
    // drv_sel (no twin output: it depends on this clock's inputs) is the
    // value drv_u takes at the edge, unless reset clears it.
    for (int a = 0; a < N; ++a) {
      const auto u = int16_t(vl::get_bits(dut_->drv_u, 16 * a, 16));
      if (cycles_ > 0) check("drv_u against the last drv_sel", a, u, drv_sel_[a]);
      drv_sel_[a] = in_.rst ? int16_t(0) : int16_t(vl::get_bits(dut_->drv_sel, 16 * a, 16));
    }
    motor(t);
    twin_.clock(in_);
    dut_->clk = 1;
    dut_->eval();
    ++cycles_;
  }

  Model& dut() { return *dut_; }
  const Twin& twin() const { return twin_; }
  int mismatches() const { return mismatches_; }

 private:
  void drive_inputs() {
    for (int a = 0; a < N; ++a) {
      const sim::QuadPins p = sim::quadrature_pins(count_[a], 2000);  // A and B; Z is random here
      in_.enc_a[a] = p.a;
      in_.enc_b[a] = p.b;
    }
    sim::apply_inputs<N>(*dut_, in_);
  }

  template <typename T>
  void check(const char* what, int axis, T rtl, T twin) {
    if (rtl == twin) return;
    if (++mismatches_ <= 10)
      ADD_FAILURE() << "cycle " << cycles_ << " " << what << "[" << axis << "]: rtl " << int64_t(rtl)
                    << " twin " << int64_t(twin);
  }

  void compare(const typename Twin::Out& t) {
    if (in_.rst) return;  // the reset cycles bring the random power-up state in
    const typename Twin::Out d = sim::read_outputs<N>(*dut_);
    check("pid_wready", 0, d.pid_wready, t.pid_wready);
    check("pid_rready", 0, d.pid_rready, t.pid_rready);
    check("pid_rvalid", 0, d.pid_rvalid, t.pid_rvalid);
    if (t.pid_rvalid) check("pid_rdata", 0, d.pid_rdata, t.pid_rdata);
    check("seg_count", 0, d.seg_count, t.seg_count);
    check("ip_busy", 0, d.ip_busy, t.ip_busy);
    check("ip_underrun", 0, d.ip_underrun, t.ip_underrun);
    check("ip_ovf", 0, d.ip_ovf, t.ip_ovf);
    check("ip_seg_cnt", 0, d.ip_seg_cnt, t.ip_seg_cnt);
    check("tick", 0, d.tick, t.tick);
    check("done", 0, d.done, t.done);
    check("smp_rdata", int(in_.smp_raddr), d.smp_rdata, t.smp_rdata);
    for (int a = 0; a < N; ++a) {
      check("pwm", a, d.pwm[a], t.pwm[a]);
      check("dir", a, d.dir[a], t.dir[a]);
      check("drv_en", a, d.drv_en[a], t.drv_en[a]);
      check("drv_u", a, d.drv_u[a], t.drv_u[a]);
      check("drv_cmd", a, d.drv_cmd[a], t.drv_cmd[a]);
      check("smp_sat", a, d.smp_sat[a], t.smp_sat[a]);
      check("pid_en", a, d.pid_en[a], t.pid_en[a]);
      check("pos", a, d.pos[a], t.pos[a]);
      check("cmd", a, d.cmd[a], t.cmd[a]);
      check("enc_err", a, d.enc[a].err, t.enc[a].err);
      check("enc_err_cnt", a, d.enc[a].err_cnt, t.enc[a].err_cnt);
      check("enc_idx_pos", a, d.enc[a].idx_pos, t.enc[a].idx_pos);
      check("enc_idx_armed", a, d.enc[a].idx_armed, t.enc[a].idx_armed);
      check("enc_idx_seen", a, d.enc[a].idx_seen, t.enc[a].idx_seen);
      check("enc_vel", a, d.enc[a].vel, t.enc[a].vel);
    }
  }

  // A motor in integers: the PWM average accelerates it, friction slows it.
  // Good enough to make the PID work against motion it causes.
  void motor(const typename Twin::Out& t) {
    for (int a = 0; a < N; ++a) {
      const int32_t push = t.pwm[a] ? (t.dir[a] ? -1 : 1) : 0;
      vel_[a] += push * 8 - vel_[a] / 256;
      acc_[a] += vel_[a];
      const int64_t steps = acc_[a] / 4096;
      acc_[a] -= steps * 4096;
      // At most one count per clock: the pins can show no more.
      count_[a] += std::clamp<int64_t>(steps, -1, 1);
    }
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> dut_;
  Twin twin_;
  int64_t acc_[N] = {};
  int16_t drv_sel_[N] = {};
  int mismatches_ = 0;
};

// Gains that close a stable loop on the testbench motor at Ts of a few
// hundred clocks, with a random spread.
template <int N>
std::deque<std::pair<uint8_t, uint32_t>> random_config(std::mt19937_64& rng) {
  std::deque<std::pair<uint8_t, uint32_t>> w;
  std::uniform_int_distribution<uint32_t> m(1, 1u << 22), s(12, 30), any;
  const auto coef = [&](uint32_t mant, uint32_t shift) { return (mant & 0xFFFFFF) | (shift << 24); };
  for (int a = 0; a < N; ++a) {
    const uint8_t base = uint8_t(a << 4);
    w.push_back({uint8_t(base | pid_reg::KP), coef(m(rng), s(rng))});
    w.push_back({uint8_t(base | pid_reg::KI), coef(m(rng), s(rng) + 8)});
    w.push_back({uint8_t(base | pid_reg::KD_A), coef(m(rng), 30)});
    w.push_back({uint8_t(base | pid_reg::KD_B), coef(m(rng), s(rng))});
    w.push_back({uint8_t(base | pid_reg::KF1), rng() % 4 ? 0 : coef(m(rng), s(rng))});
    w.push_back({uint8_t(base | pid_reg::OLIM), rng() % 3 ? 0 : any(rng) % 40000});
    // Deadband and error clamp sometimes, so ERR and FOLLOW differ.
    w.push_back({uint8_t(base | pid_reg::DBAND), rng() % 3 ? 0 : uint32_t(rng() % 8)});
    w.push_back({uint8_t(base | pid_reg::ELIM), rng() % 3 ? 0 : uint32_t(20 + rng() % 200)});
    w.push_back({uint8_t(base | pid_reg::CTRL), uint32_t(rng() % 5 != 0)});
  }
  w.push_back({uint8_t(pid_reg::GLOBAL_AXIS << 4 | pid_reg::G_TS), uint32_t(50 + rng() % 600)});
  return w;
}

template <typename Model, int N>
void random_run(uint32_t seed, uint64_t cycles) {
  MotionCosim<Model, N> s(seed);
  std::mt19937_64& rng = s.rng_;
  SegGen gen(seed);
  gen.max_line = 300;
  gen.max_radius = 400;
  std::deque<uint32_t> words;
  host::Vec3 at{0, 0, 0};
  auto cfg = random_config<N>(rng);
  for (int a = 0; a < N; ++a) {
    s.in_.drv_allow[a] = true;
    s.in_.enc_filt[a] = uint32_t(rng() % 4);
  }
  uint64_t reads = 0, ticks = 0;
  for (uint64_t c = 0; c < cycles; ++c) {
    auto& in = s.in_;
    const auto o = s.twin().outputs(in.pid_we);
    // PID port: writes from the queue, the occasional read when no write.
    if (in.pid_we && o.pid_wready) cfg.pop_front();
    if (in.pid_re && o.pid_rready) ++reads;
    if (cfg.empty() && rng() % 20000 == 0) cfg = random_config<N>(rng);
    in.pid_we = !cfg.empty() && rng() % 4 != 0;
    if (in.pid_we) {
      in.pid_waddr = cfg.front().first;
      in.pid_wdata = cfg.front().second;
    }
    in.pid_re = rng() % 64 == 0;
    in.pid_raddr = uint8_t(rng() % 2 ? (rng() % N) << 4 | rng() % 16 : 0xF0 | rng() % 3);
    // Segments, a word at a time when there is room for a whole one.
    in.seg_wr = false;
    if (words.empty() && o.seg_count < 400 && rng() % 50 == 0) {
      const host::PlannedSegment g = rng() % 3 ? gen.line(at) : gen.arc(at);
      for (uint32_t w : seg::pack(g.seg)) words.push_back(w);
      at = g.end;
    }
    if (!words.empty() && rng() % 3 != 0) {
      in.seg_wr = true;
      in.seg_wdata = words.front();
      words.pop_front();
    }
    in.ip_hold = rng() % 5000 == 0 ? !in.ip_hold : in.ip_hold;
    in.ip_clr = rng() % 3000 == 0;
    in.ip_abort = false;
    in.ip_set = rng() % 7000 == 0 ? uint8_t(1 + rng() % 7) : 0;
    for (int a = 0; a < 3; ++a) in.ip_set_pos[a] = int32_t(rng() % 2000) - 1000;
    if (in.ip_set && !o.ip_busy)
      for (int a = 0; a < 3; ++a)
        if (in.ip_set >> a & 1) at[size_t(a)] = in.ip_set_pos[a];
    // Handwheel jog strobes: they act only while the interpolator is idle;
    // segments move relative to where they start, so a jog just offsets them.
    in.ip_jog = rng() % 3000 == 0 ? uint8_t(1 + rng() % 7) : 0;
    in.ip_jog_neg = rng() % 2;
    // Encoders and drive.
    for (int a = 0; a < N; ++a) {
      in.enc_idx_arm[a] = rng() % 4000 == 0;
      in.enc_idx_disarm[a] = rng() % 20000 == 0;
      in.enc_err_clr[a] = rng() % 5000 == 0;
      in.enc_z[a] = rng() % 3000 == 0 ? !in.enc_z[a] : in.enc_z[a];
      in.enc_latch[a] = rng() % 3000 == 0;
      in.enc_dir_inv[a] = rng() % 50000 == 0 ? !in.enc_dir_inv[a] : in.enc_dir_inv[a];
      in.enc_idx_clr_en[a] = rng() % 2;
      if (rng() % 20000 == 0) in.drv_allow[a] = !in.drv_allow[a];
      if (rng() % 20000 == 0) in.drv_ovr[a] = !in.drv_ovr[a];
      in.drv_ovr_we[a] = rng() % 500 == 0;
    }
    in.drv_ovr_val = int16_t(rng());
    // Sample RAM: every word, including the unused fields and absent axes.
    in.smp_raddr = uint8_t(rng() % 32);
    in.rst = rng() % 150000 == 0;
    ticks += o.tick;
    s.cycle();
    if (s.mismatches() > 10) break;
  }
  EXPECT_EQ(s.mismatches(), 0);
  EXPECT_GT(ticks, cycles / 700);
  EXPECT_GT(reads, 0u);
  std::printf("motion_core NAXES=%d: %llu cycles, %llu samples bit-exact\n", N, (unsigned long long)cycles,
              (unsigned long long)ticks);
}

TEST(MotionCoreRtl, RandomThreeAxes) {
  random_run<Vmotion_core, 3>(1, 400000);
}
TEST(MotionCoreRtl, RandomTwoAxes) {
  random_run<Vmotion_core2, 2>(2, 400000);
}

// A sample's drive reaches the pins LATENCY + 2 clocks after its tick, all
// axes in the same clock; PWM duty is |u| in steps of 2^(15-PWM_BITS).
TEST(MotionCoreRtl, DriveTimingAndDuty) {
  MotionCosim<Vmotion_core2, 2> s(3);
  using Twin = MotionCore<2>;
  auto& in = s.in_;
  // P only, large gain: the output saturates at the limits we choose.
  const uint32_t kp = (1u << 22) | (16u << 24);  // 2^22 * 2^-16 = 64 per count
  const std::pair<uint8_t, uint32_t> cfg[] = {{0x00, kp}, {0x10, kp}, {0x07, 20000}, {0x17, 5000},
                                              {0x0F, 1},  {0x1F, 1},  {0xF0, 400}};
  for (const auto& [addr, data] : cfg) {
    in.pid_we = true;
    in.pid_waddr = addr;
    in.pid_wdata = data;
    while (!s.twin().outputs(true).pid_wready) s.cycle();
    s.cycle();
  }
  in.pid_we = false;
  in.drv_allow[0] = in.drv_allow[1] = true;
  // Command +1000 on both axes (the motor stays put: no PWM before this).
  in.ip_set = 7;
  in.ip_set_pos[0] = 1000;
  in.ip_set_pos[1] = -1000;
  s.cycle();
  in.ip_set = 0;
  while (!s.twin().outputs().tick) s.cycle();
  uint64_t t0 = s.cycles_;
  s.cycle();
  // Each axis's drive takes its output as the sweep makes it, the pins a
  // clock after: axis 0 first, axis 1 one slot (18 clocks) later, both
  // before the sweep's done.
  while (s.twin().outputs().drv_u[0] == 0) s.cycle();
  EXPECT_EQ(s.cycles_ - t0, uint64_t(Twin::drv_clock(0) + 2));
  EXPECT_EQ(s.twin().outputs().drv_u[0], 20000);
  EXPECT_EQ(s.twin().outputs().drv_u[1], 0);
  while (s.twin().outputs().drv_u[1] == 0) s.cycle();
  EXPECT_EQ(s.cycles_ - t0, uint64_t(Twin::drv_clock(1) + 2));
  EXPECT_LT(s.cycles_ - t0, uint64_t(Twin::latency + 2));
  EXPECT_EQ(s.twin().outputs().drv_u[0], 20000);
  EXPECT_EQ(s.twin().outputs().drv_u[1], -5000);
  // Over one PWM period the high clocks are the duty.
  int high[2] = {}, dir1 = 0;
  const int period = 1 << Twin::pwm_bits;
  for (int c = 0; c < period; ++c) {
    const auto o = s.twin().outputs();
    high[0] += o.pwm[0];
    high[1] += o.pwm[1];
    dir1 += o.dir[1];
    s.cycle();
  }
  EXPECT_EQ(high[0], int(Twin::duty(20000)));
  EXPECT_EQ(high[0], 20000 >> (15 - Twin::pwm_bits));
  EXPECT_EQ(high[1], 5000 >> (15 - Twin::pwm_bits));
  EXPECT_EQ(dir1, period);
  // Dropping the allow takes the drive off in the next clock.
  in.drv_allow[0] = false;
  s.cycle();
  EXPECT_EQ(s.twin().outputs().drv_u[0], 0);
  EXPECT_FALSE(s.twin().outputs().pwm[0]);
  EXPECT_FALSE(s.twin().outputs().drv_en[0]);
  EXPECT_TRUE(s.twin().outputs().drv_en[1]);
  // Full scale is always on.
  EXPECT_EQ(Twin::duty(-32768), uint32_t(period));
  EXPECT_EQ(Twin::duty(32767), uint32_t(period - 1));
  EXPECT_EQ(s.mismatches(), 0);
}

}  // namespace
}  // namespace mc::test
