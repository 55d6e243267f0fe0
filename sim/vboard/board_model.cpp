#include "sim/vboard/board_model.hpp"

#include "Vmotioncore_icebreaker.h"
#include "Vmotioncore_icebreaker___024root.h"
#include "verilated.h"

namespace mc::sim {
namespace {

// The twin: stepped where something happens, advanced over the rest.
class TwinBoard final : public BoardModel {
 public:
  uint32_t run(const IcebreakerPins& p, uint32_t limit, int32_t* drive, UartReceiver& line) override {
    const uint32_t n = b_.idle_clocks(p, limit);
    if (n > 0) {
      // EN holds through the stretch; PWM follows its counter.
      if (b_.drv_en())
        for (int a = 0; a < kBoardAxes; ++a) drive[a] += b_.drive_in(a, 0, n);
      advance(p, n, line, nullptr, 0);
      return n;
    }
    b_.step(p);
    line.clock(b_.tx());
    ++stepped_;
    sp_high_ += b_.sp_pwm();
    // seg_wr_o and the word it writes, registered: the queue takes them at the next edge.
    const auto& regs = b_.u_board.u_regs;
    if (seg_tap_ && regs.r.seg_wr_o) seg_tap_->push_back(regs.data_o());
    for (int a = 0; a < kBoardAxes; ++a)
      if (b_.drv_en() && b_.pwm(a)) drive[a] += b_.dir(a) ? -1 : 1;
    return 1;
  }
  bool drv_en() const override { return b_.drv_en(); }
  bool pwm(int a) const override { return b_.pwm(a); }
  bool dir(int a) const override { return b_.dir(a); }
  uint32_t idle_clocks(const IcebreakerPins& p, uint32_t limit) override { return b_.idle_clocks(p, limit); }
  int32_t idle_drive(int a, uint32_t from, uint32_t n) const override {
    return b_.drv_en() ? b_.drive_in(a, from, n) : 0;
  }
  uint32_t idle_drive_runs(int a, uint32_t from, uint32_t k, uint32_t max) const override {
    return b_.drv_en() ? b_.drive_runs(a, from, k, max) : max;
  }
  void advance(const IcebreakerPins& p, uint32_t n, UartReceiver& line, const PinChange* ch,
               size_t count) override {
    before_stretch(n, line);
    b_.advance(p, n, ch, count);
  }
  size_t idle_foldable(const PinChange* ch, size_t count) const override { return b_.foldable(ch, count); }
  void idle_tx(uint32_t n, const Levels& f) const override { b_.tx_levels(n, f); }
  uint32_t line_clocks(const IcebreakerPins& p, uint32_t limit, const RxLine& rx) override {
    return b_.line_clocks(p, limit, rx);
  }
  void advance_line(const IcebreakerPins& p, uint32_t n, const RxLine& rx, UartReceiver& line,
                    const PinChange* ch, size_t count) override {
    before_stretch(n, line);
    b_.advance_line(p, n, rx, ch, count);
  }
  bool sp_pwm() const override { return b_.sp_pwm(); }
  bool sp_en() const override { return b_.sp_en(); }
  bool sp_dir() const override { return b_.sp_dir(); }
  bool flood() const override { return b_.flood(); }

 private:
  // What the n clocks of a stretch show before the board does them: SP_PWM's
  // high clocks, and TX after each into `line`.
  void before_stretch(uint32_t n, UartReceiver& line) {
    sp_high_ += b_.sp_high_in(n);
    b_.tx_levels(n, [&](bool level, uint32_t clocks) { line.clock_n(level, clocks); });
  }
  // Built as the Verilated top is (sim/vboard/CMakeLists.txt): a step
  // generator on every axis, STEP_CFG choosing which axes use it.
  MotioncoreIcebreaker<kBoardAxes, 12'000'000, 1'000'000, true, MC_VBOARD_STEPPERS> b_;
};

// The Verilated top, one clock per call; the harness writes only the input
// ports whose level changed.
class RtlBoard final : public BoardModel {
 public:
  explicit RtlBoard(uint32_t seed) {
    ctx_ = std::make_unique<VerilatedContext>();
    // An iCE40 configures every flip-flop and block RAM to zero; a seed
    // asks for Verilator's random power-up state instead.
    ctx_->randReset(seed ? 2 : 0);
    ctx_->randSeed(int(seed & 0x7fffffff));
    top_ = std::make_unique<Vmotioncore_icebreaker>(ctx_.get(), "board");
    Vmotioncore_icebreaker& t = *top_;
    enc_[0] = {&t.X_ENC_A, &t.X_ENC_B, &t.X_LIM};
    enc_[1] = {&t.Y_ENC_A, &t.Y_ENC_B, &t.Y_LIM};
    enc_[2] = {&t.Z_ENC_A, &t.Z_ENC_B, &t.Z_LIM};
    drv_[0] = {&t.X_PWM, &t.X_DIR};
    drv_[1] = {&t.Y_PWM, &t.Y_DIR};
    drv_[2] = {&t.Z_PWM, &t.Z_DIR};
    t.CLK = 0;
    write_all(last_);
    t.eval();
  }
  ~RtlBoard() override { top_->final(); }

  uint32_t run(const IcebreakerPins& p, uint32_t /*limit*/, int32_t* drive, UartReceiver& line) override {
    Vmotioncore_icebreaker& t = *top_;
    if (!same(p, last_)) {
      write_all(p);
      last_ = p;
    }
    t.CLK = 1;
    t.eval();
    t.CLK = 0;
    t.eval();
    line.clock(t.TX);
    ++stepped_;
    // The executor's queue write and its word (mc_regs' seg_wr_o, seg_wdata_o = data).
    if (seg_tap_ && t.rootp->motioncore_icebreaker__DOT__u_board__DOT__seg_wr)
      seg_tap_->push_back(t.rootp->motioncore_icebreaker__DOT__u_board__DOT__u_regs__DOT__data);
    for (int a = 0; a < kBoardAxes; ++a)
      if (t.DRV_EN && *drv_[a].pwm) drive[a] += *drv_[a].dir ? -1 : 1;
    sp_high_ += t.SP_PWM;
    return 1;
  }
  bool sp_pwm() const override { return top_->SP_PWM; }
  bool sp_en() const override { return top_->SP_EN; }
  bool sp_dir() const override { return top_->SP_DIR; }
  bool flood() const override { return top_->FLOOD; }
  bool drv_en() const override { return top_->DRV_EN; }
  bool pwm(int a) const override { return *drv_[a].pwm; }
  bool dir(int a) const override { return *drv_[a].dir; }

 private:
  struct EncPorts {
    uint8_t *a, *b, *lim;
  };
  struct DrvPorts {
    const uint8_t *pwm, *dir;
  };
  static bool same(const IcebreakerPins& x, const IcebreakerPins& y) {
    for (int a = 0; a < kBoardAxes; ++a)
      if (x.enc_a[a] != y.enc_a[a] || x.enc_b[a] != y.enc_b[a] || x.lim[a] != y.lim[a]) return false;
    return x.rx == y.rx && x.btn_n == y.btn_n && x.estop == y.estop && x.probe == y.probe &&
           x.hw_a == y.hw_a && x.hw_b == y.hw_b;
  }
  void write_all(const IcebreakerPins& p) {
    Vmotioncore_icebreaker& t = *top_;
    t.RX = p.rx;
    t.BTN_N = p.btn_n;
    t.ESTOP = p.estop;
    t.PROBE = p.probe;
    t.HW_A = p.hw_a;
    t.HW_B = p.hw_b;
    for (int a = 0; a < kBoardAxes; ++a) {
      *enc_[a].a = p.enc_a[a];
      *enc_[a].b = p.enc_b[a];
      *enc_[a].lim = p.lim[a];
    }
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmotioncore_icebreaker> top_;
  EncPorts enc_[kBoardAxes]{};
  DrvPorts drv_[kBoardAxes]{};
  IcebreakerPins last_;
};

}  // namespace

std::unique_ptr<BoardModel> make_board_model(BoardEngine e, uint32_t seed) {
  if (e == BoardEngine::Rtl) return std::make_unique<RtlBoard>(seed);
  return std::make_unique<TwinBoard>();
}

}  // namespace mc::sim
