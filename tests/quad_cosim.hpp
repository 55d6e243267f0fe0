// C/RTL co-simulation of quad_decoder: the Verilated RTL and the hls/ twin
// run in lock-step on the same inputs, every output compared every clock.
// Drop-in for QuadTwinSimT in QuadBench and the property suite.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>

#include "quad_harness.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc::test {

// Verilated RTL (Model, whose parameters match Twin's) and twin in lock-step.
template <typename Model, typename Twin>
class QuadCosimT {
 public:
  using TwinT = Twin;
  explicit QuadCosimT(uint32_t seed) : ctx_(random_context(seed)) {
    dut_ = std::make_unique<Model>(ctx_.get(), "quad_decoder");
    // Reset, pins low, not scoreboarded: whatever the RTL powered up in, three
    // clocks of reset must bring it to the twin's state.
    QuadIn in;
    in.rst = true;
    for (int i = 0; i < 4; ++i) {
      drive(in);
      clock();
      twin_.step(in);
    }
  }
  ~QuadCosimT() { dut_->final(); }
  QuadCosimT(const QuadCosimT&) = delete;
  QuadCosimT& operator=(const QuadCosimT&) = delete;

  QuadOut cycle(const QuadIn& in) {
    drive(in);
    clock();
    const QuadOut rtl = read();
    const QuadOut tw = twin_.step(in);
    if (rtl != tw && ++mismatches_ <= 5)
      ADD_FAILURE() << "clock " << cycles_ << ": rtl " << describe(rtl) << "\n  twin " << describe(tw);
    ++cycles_;
    return rtl;
  }
  int mismatches() const { return mismatches_; }

 private:
  static constexpr int kVelW = Twin::vel_w;

  void drive(const QuadIn& in) {
    dut_->rst = in.rst;
    dut_->filt_len_i = in.filt_len & ones(Twin::filt_w);
    dut_->dir_inv_i = in.dir_inv;
    dut_->idx_clr_en_i = in.idx_clr_en;
    dut_->pos_load_i = in.pos_load;
    dut_->pos_load_val_i = uint32_t(in.pos_load_val);
    dut_->idx_arm_i = in.idx_arm;
    dut_->idx_disarm_i = in.idx_disarm;
    dut_->err_clr_i = in.err_clr;
    dut_->sample_i = in.sample;
    dut_->enc_a_i = in.a;
    dut_->enc_b_i = in.b;
    dut_->enc_z_i = in.z;
    dut_->latch_i = in.latch;
  }
  void clock() {
    dut_->clk = 0;
    dut_->eval();
    dut_->clk = 1;
    dut_->eval();
    ctx_->timeInc(1);
  }
  QuadOut read() const {
    QuadOut o;
    o.pos = int32_t(dut_->pos_o);
    o.idx_pos = int32_t(dut_->idx_pos_o);
    o.idx_armed = dut_->idx_armed_o;
    o.idx_seen = dut_->idx_seen_o;
    o.err = dut_->err_o;
    o.err_cnt = dut_->err_cnt_o;
    o.vel = int32_t(sext(dut_->vel_o, kVelW));
    o.age = dut_->age_o;
    o.a = dut_->a_o;
    o.b = dut_->b_o;
    o.z = dut_->z_o;
    return o;
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> dut_;
  Twin twin_;
  uint64_t cycles_ = 0;
  int mismatches_ = 0;
};

}  // namespace mc::test
