// C/RTL co-simulation harness for pid_core: one testbench drives the Verilated
// RTL cycle by cycle and the hls/ twin at the sample level, and compares every
// output of every sample. Writes and the sampling instant are taken from the
// RTL's own handshake (a write accepted in the tick cycle counts for that
// sample), so the twin sees exactly what the hardware saw.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <sstream>
#include <string>

#include "hls/pid_core.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc::test {

template <typename A>
int64_t get_acc(const A& arr, int i) {
  return sext(uint64_t(arr[i]), ACC_W);
}

// Model: a Verilated pid_core (V<prefix>); NAXES and SERVO must match its
// parameters.
template <typename Model, int NAXES, bool SERVO = true>
class PidCosimT {
 public:
  static constexpr int kAxes = NAXES;
  explicit PidCosimT(uint32_t seed) : ctx_(random_context(seed)) {
    dut_ = std::make_unique<Model>(ctx_.get(), "pid_core");
    twin_.reset();
    // Reset cycles are not scoreboarded: whatever random state the model
    // powered up in, the synchronous reset must bring it to the twin's.
    dut_->rst = 1;
    dut_->cfg_we = 0;
    dut_->cfg_re = 0;
    for (int i = 0; i < 4; ++i) {
      settle();
      edge();
    }
    dut_->rst = 0;
  }
  ~PidCosimT() { dut_->final(); }
  PidCosimT(const PidCosimT&) = delete;
  PidCosimT& operator=(const PidCosimT&) = delete;

  // Values presented to the RTL on every following cycle until changed.
  void set_inputs(const std::array<int32_t, kAxes>& cmd, const std::array<int32_t, kAxes>& fb) {
    cmd_ = cmd;
    fb_ = fb;
  }

  // Queue a configuration write; it is issued as soon as the core accepts it.
  void write(uint8_t addr, uint32_t data) { wq_.push_back({addr, data}); }

  // Read a register through the RTL port and check it against the twin.
  uint32_t read(uint8_t addr) {
    flush_writes();
    rd_active_ = true;
    rd_addr_ = addr;
    rd_done_ = false;
    for (int guard = 0; !rd_done_; ++guard) {
      if (guard > 4 * Vlat() + 16) {
        ADD_FAILURE() << "read 0x" << std::hex << int(addr) << " never accepted";
        rd_active_ = false;
        return 0;
      }
      cycle();
    }
    rd_active_ = false;
    settle();
    EXPECT_TRUE(dut_->cfg_rvalid);
    EXPECT_EQ(dut_->cfg_rdata, rd_expect_) << "read-back of 0x" << std::hex << int(addr);
    return dut_->cfg_rdata;
  }

  // Run until the first sample taken after this call (so with the inputs
  // set before it) completes; false on timeout. Every completed sample, this
  // one and any in flight before it, is compared in full.
  bool run_sample(uint64_t max_cycles = 1u << 20) {
    flush_writes();
    const uint64_t target = ticks_ + 1;
    for (uint64_t c = 0; c < max_cycles && samples_ < target; ++c) cycle();
    return samples_ >= target;
  }

  void flush_writes() {
    for (int guard = 0; !wq_.empty(); ++guard) {
      cycle();
      if (guard > 1 << 20) {
        ADD_FAILURE() << "writes never accepted";
        return;
      }
    }
  }

  // One clock cycle: present inputs, let the scoreboard observe the cycle,
  // then the rising edge.
  void cycle() {
    dut_->cfg_we = wq_.empty() ? 0 : 1;
    dut_->cfg_re = rd_active_ && !rd_done_;
    dut_->cfg_raddr = rd_addr_;
    if (!wq_.empty()) {
      dut_->cfg_waddr = wq_.front().addr;
      dut_->cfg_wdata = wq_.front().data;
    }
    for (int a = 0; a < kAxes; ++a) {
      put32(dut_->cmd_i, a, uint32_t(cmd_[a]));
      put32(dut_->fb_i, a, uint32_t(fb_[a]));
    }
    settle();
    // At the shortest Ts a sweep ends in the cycle the next one is ticked:
    // compare the finished sample before the twin computes the next.
    if (dut_->done_o) {
      EXPECT_TRUE(pending_) << "done_o without a sample";
      last_latency_ = cycles_ - last_tick_;
      compare();
      pending_ = false;
      ++samples_;
    }
    if (dut_->cfg_re && dut_->cfg_rready) {
      rd_expect_ = twin_.read(rd_addr_);
      rd_done_ = true;
    }
    // A write accepted in the tick cycle lands before that sample's sweep.
    if (dut_->cfg_we && dut_->cfg_wready) {
      twin_.write(wq_.front().addr, wq_.front().data);
      wq_.pop_front();
    }
    if (dut_->tick_o) {
      EXPECT_FALSE(pending_) << "tick while a sweep is still running";
      ++ticks_;
      if (last_tick_ != 0) last_period_ = cycles_ - last_tick_;
      last_tick_ = cycles_;
      twin_.sample(cmd_.data(), fb_.data());
      pending_ = true;
    }
    edge();
  }

  const PidCore<kAxes, SERVO>& twin() const { return twin_; }
  Model& dut() { return *dut_; }
  uint64_t samples() const { return samples_; }
  uint64_t cycles() const { return cycles_; }
  uint64_t last_period() const { return last_period_; }
  uint64_t last_latency() const { return last_latency_; }
  int32_t u(int a) const { return int16_t(uint16_t(get_bits(dut_->u_o, 16 * a, 16))); }
  int32_t err(int a) const { return int32_t(get_bits(dut_->err_o, 32 * a, 32)); }
  bool sat(int a) const { return (dut_->sat_o >> a) & 1; }
  int mismatches() const { return mismatches_; }
  static int Vlat() { return PidCore<kAxes, SERVO>::latency; }

 private:
  void settle() {
    dut_->clk = 0;
    dut_->eval();
  }
  void edge() {
    dut_->clk = 1;
    dut_->eval();
    ctx_->timeInc(1);
    ++cycles_;
  }

  void compare() {
    for (int a = 0; a < kAxes; ++a) {
      // The whole state too, as the RTL's state RAMs hold it (st_* is the
      // RTL's simulation-only view of them): a one-LSB integrator difference
      // can hide below the output's rounding for a long time, and a history
      // word in the wrong ring slot only shows when the input moves.
      const auto& r = *dut_->rootp;
      const PidState& ts = twin_.state(a);
      const int64_t si = get_acc(r.pid_core__DOT__st_i, a);
      const int64_t sd = get_acc(r.pid_core__DOT__st_d, a);
      const auto e1 = int32_t(r.pid_core__DOT__st_e1[a]);
      const auto c1 = int32_t(r.pid_core__DOT__st_c1[a]);
      const auto c2 = int32_t(r.pid_core__DOT__st_c2[a]);
      const bool ok = u(a) == twin_.u(a) && err(a) == twin_.err(a) && sat(a) == twin_.sat(a) && si == ts.i &&
                      sd == ts.d && e1 == ts.e1 && c1 == ts.c1 && c2 == ts.c2;
      if (!ok && ++mismatches_ <= 5) {
        std::ostringstream os;
        os << "sample " << samples_ << " axis " << a << ": rtl u=" << u(a) << " err=" << err(a)
           << " sat=" << sat(a) << ", twin u=" << twin_.u(a) << " err=" << twin_.err(a)
           << " sat=" << twin_.sat(a) << "; state rtl i=" << si << " d=" << sd << " e1=" << e1 << " c1=" << c1
           << " c2=" << c2 << ", twin i=" << ts.i << " d=" << ts.d << " e1=" << ts.e1 << " c1=" << ts.c1
           << " c2=" << ts.c2 << " (cmd=" << cmd_[a] << " fb=" << fb_[a] << ")";
        ADD_FAILURE() << os.str();
      }
    }
  }

  struct W {
    uint8_t addr;
    uint32_t data;
  };
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> dut_;
  PidCore<kAxes, SERVO> twin_;
  std::deque<W> wq_;
  std::array<int32_t, kAxes> cmd_{}, fb_{};
  uint64_t cycles_ = 0, samples_ = 0, ticks_ = 0, last_tick_ = 0, last_period_ = 0, last_latency_ = 0;
  bool pending_ = false;
  bool rd_active_ = false, rd_done_ = false;
  uint8_t rd_addr_ = 0;
  uint32_t rd_expect_ = 0;
  int mismatches_ = 0;
};

}  // namespace mc::test
