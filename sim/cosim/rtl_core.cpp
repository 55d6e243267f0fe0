#include "sim/cosim/rtl_core.hpp"

#include <verilated_fst_c.h>

#include "Vmotion_core2.h"
#include "host/base/errors.hpp"
#include "sim/cosim/vl_motion.hpp"
#include "verilated.h"

namespace mc::sim {
namespace {

class RtlCore final : public CoreModel {
 public:
  explicit RtlCore(const std::string& fst_path) : ctx_(std::make_unique<VerilatedContext>()) {
    dut_ = std::make_unique<Vmotion_core2>(ctx_.get(), "motion_core");
    if (!fst_path.empty()) {
      ctx_->traceEverOn(true);
      fst_ = std::make_unique<VerilatedFstC>();
      dut_->trace(fst_.get(), 99);
      fst_->open(fst_path.c_str());
      if (!fst_->isOpen())
        throw mc::host::InputError("--trace", "'" + fst_path + "'", "a writable file path");
    }
  }
  ~RtlCore() override {
    dut_->final();
    if (fst_) fst_->close();
  }
  RtlCore(const RtlCore&) = delete;
  RtlCore& operator=(const RtlCore&) = delete;

  CoreOut cycle(const CoreIn& in) override {
    apply_inputs<kCoreAxes>(*dut_, in);
    dut_->clk = 0;
    dut_->eval();
    const CoreOut o = read_outputs<kCoreAxes>(*dut_);
    if (fst_) fst_->dump(2 * clock_);
    dut_->clk = 1;
    dut_->eval();
    if (fst_) fst_->dump(2 * clock_ + 1);
    ++clock_;
    return o;
  }
  std::optional<Skipped> try_skip(const CoreIn&, uint32_t) override { return std::nullopt; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmotion_core2> dut_;
  std::unique_ptr<VerilatedFstC> fst_;
  uint64_t clock_ = 0;
};

}  // namespace

std::unique_ptr<CoreModel> make_rtl_core(const std::string& fst_path) {
  return std::make_unique<RtlCore>(fst_path);
}

}  // namespace mc::sim
