#include "sim/cosim/rtl_core.hpp"

#include <verilated_fst_c.h>

#include <cstring>
#include <ctime>
#include <type_traits>

#include "Vmotion_core2.h"
#include "Vmotion_core2_trace.h"
#include "host/base/errors.hpp"
#include "sim/cosim/vl_motion.hpp"
#include "verilated.h"

namespace mc::sim {

namespace {

// The encoder pins: the only inputs the co-simulation moves every few
// clocks once the core is configured.
template <typename Model>
void apply_encoders(Model& d, const CoreIn& in) {
  uint32_t ea = 0, eb = 0, ez = 0;
  for (int a = 0; a < kCoreAxes; ++a) {
    ea |= uint32_t(in.enc_a[a]) << a;
    eb |= uint32_t(in.enc_b[a]) << a;
    ez |= uint32_t(in.enc_z[a]) << a;
  }
  vl::set(d.enc_a, ea);
  vl::set(d.enc_b, eb);
  vl::set(d.enc_z, ez);
}

// Everything in the inputs but the encoder pins equal.
bool same_but_encoders(CoreIn a, const CoreIn& b) {
  for (int x = 0; x < kCoreAxes; ++x) {
    a.enc_a[x] = b.enc_a[x];
    a.enc_b[x] = b.enc_b[x];
    a.enc_z[x] = b.enc_z[x];
  }
  return a == b;
}

// The outputs the co-simulation reads (CoreModel::cycle), and only those
// (the queue level paces the segment stream):
// reading every port each clock costs a fifth of the model's own time.
template <typename Model>
CoreOut read_used(const Model& d) {
  CoreOut o;
  o.pid_wready = d.pid_wready;
  o.seg_count = int(d.seg_count);
  o.ip_underrun = d.ip_underrun;
  o.tick = d.tick;
  o.done = d.done;
  for (int a = 0; a < kCoreAxes; ++a) {
    o.pwm[a] = (d.pwm_o >> a) & 1;
    o.dir[a] = (d.dir_o >> a) & 1;
    o.drv_en[a] = (d.drv_en_o >> a) & 1;
    o.drv_u[a] = int16_t(vl::get_bits(d.drv_u, 16 * a, 16));
    o.drv_cmd[a] = int16_t(vl::get_bits(d.drv_cmd, 16 * a, 16));
    o.cmd[a] = int32_t(vl::get_bits(d.cmd, 32 * a, 32));
  }
  return o;
}

// Model: Vmotion_core2 (fast) or Vmotion_core2_trace (with an FST open).
template <typename Model>
class RtlCore final : public CoreModel {
 public:
  explicit RtlCore(const std::string& fst_path) : ctx_(std::make_unique<VerilatedContext>()) {
    dut_ = std::make_unique<Model>(ctx_.get(), "motion_core");
    if constexpr (std::is_same_v<Model, Vmotion_core2_trace>) {
      ctx_->traceEverOn(true);
      fst_ = std::make_unique<VerilatedFstC>();
      dut_->trace(fst_.get(), 99);
      fst_->open(fst_path.c_str());
      if (!fst_->isOpen())
        throw mc::host::InputError("--trace", "'" + fst_path + "'", "a writable file path");
    }
    apply_inputs<kCoreAxes>(*dut_, last_);
  }
  ~RtlCore() override {
    dut_->final();
    if (fst_) fst_->close();
  }
  RtlCore(const RtlCore&) = delete;
  RtlCore& operator=(const RtlCore&) = delete;

  CoreOut cycle(const CoreIn& in) override {
    // The harness writes the ports whose value changed: the encoder pins,
    // or (configuring, commanding) all of them.
    if (same_but_encoders(in, last_)) {
      apply_encoders(*dut_, in);
    } else {
      apply_inputs<kCoreAxes>(*dut_, in);
    }
    std::memcpy(&last_, &in, sizeof last_);
    dut_->clk = 0;
    dut_->eval();
    const CoreOut o = read_used(*dut_);
    if (fst_) fst_->dump(2 * clock_);
    dut_->clk = 1;
    dut_->eval();
    if (fst_) fst_->dump(2 * clock_ + 1);
    ++clock_;
    return o;
  }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Model> dut_;
  std::unique_ptr<VerilatedFstC> fst_;
  CoreIn last_;
  uint64_t clock_ = 0;
};

}  // namespace

std::unique_ptr<CoreModel> make_rtl_core(const std::string& fst_path) {
  if (fst_path.empty()) return std::make_unique<RtlCore<Vmotion_core2>>(fst_path);
  return std::make_unique<RtlCore<Vmotion_core2_trace>>(fst_path);
}

double bare_rtl_clocks_per_s(uint64_t clocks) {
  VerilatedContext ctx;
  Vmotion_core2 d(&ctx, "motion_core");
  apply_inputs<kCoreAxes>(d, CoreIn{});
  const auto edge = [&] {
    d.clk = 0;
    d.eval();
    d.clk = 1;
    d.eval();
  };
  d.rst = 1;
  for (int i = 0; i < 4; ++i) edge();
  d.rst = 0;
  // CPU time, as the co-simulation runs compare on it.
  timespec a{}, b{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  for (uint64_t i = 0; i < clocks; ++i) edge();
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  const double s = double(b.tv_sec - a.tv_sec) + 1e-9 * double(b.tv_nsec - a.tv_nsec);
  d.final();
  return double(clocks) / s;
}

}  // namespace mc::sim
