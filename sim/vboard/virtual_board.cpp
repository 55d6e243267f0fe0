#include "sim/vboard/virtual_board.hpp"

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "Vmotioncore_icebreaker.h"
#include "host/base/errors.hpp"
#include "sim/plant/dc_motor.hpp"
#include "sim/vboard/uart_model.hpp"
#include "verilated.h"

namespace mc::sim {

namespace {

// The board top's parameters (rtl/motioncore_icebreaker.v defaults, as built).
constexpr long kBoardBaud = 1'000'000;

uint32_t whole_clocks_per_step(const MachineConfig& m) {
  const double k = m.clock_hz * m.plant_dt_s;
  if (!(k >= 2) || std::fabs(k - std::round(k)) > 1e-6)
    throw mc::host::InputError("plant_dt_s * clock_hz (" + m.source + ")", std::to_string(k),
                               "a whole number of at least 2 board clocks per plant step");
  return uint32_t(std::llround(k));
}

std::string sys_error(const char* call) {
  return std::string(call) + " failed: " + std::strerror(errno);
}

}  // namespace

struct VirtualBoard::Impl {
  // One axis slot of the board: its pins and, when configured, its plant.
  struct Slot {
    uint8_t *enc_a, *enc_b, *enc_z;
    const uint8_t *pwm, *dir, *en;
    std::unique_ptr<AxisPlant> plant;
    int cpr = 0;
    double supply_v = 0;
    int64_t shown = 0, emit_from = 0, emit_n = 0;  // encoder edges of the current step
    int32_t drive_sum = 0;                         // clocks +1 / -1 with the bridge on, this step
  };

  Impl(const MachineConfig& cfg, uint32_t seed)
      : m(cfg),
        k(whole_clocks_per_step(cfg)),
        cpb(uart_clocks_per_bit(long(std::llround(cfg.clock_hz)), kBoardBaud)),
        tx(cpb),
        rx(cpb) {
    if (m.axes.size() > size_t(kBoardAxes))
      throw mc::host::InputError("axes (" + m.source + ")", std::to_string(m.axes.size()),
                                 "at most " + std::to_string(kBoardAxes) + " (the board's x, y, z)");
    ctx = std::make_unique<VerilatedContext>();
    // An iCE40 configures every flip-flop and block RAM to zero; a seed
    // asks for Verilator's random power-up state instead.
    ctx->randReset(seed ? 2 : 0);
    ctx->randSeed(int(seed & 0x7fffffff));
    top = std::make_unique<Vmotioncore_icebreaker>(ctx.get(), "board");
    Vmotioncore_icebreaker& t = *top;
    slot[0] = {&t.X_ENC_A, &t.X_ENC_B, &t.X_ENC_Z, &t.X_PWM, &t.X_DIR, &t.X_EN, {}, 0, 0, 0, 0, 0, 0};
    slot[1] = {&t.Y_ENC_A, &t.Y_ENC_B, &t.Y_ENC_Z, &t.Y_PWM, &t.Y_DIR, &t.Y_EN, {}, 0, 0, 0, 0, 0, 0};
    slot[2] = {&t.Z_ENC_A, &t.Z_ENC_B, &t.Z_ENC_Z, &t.Z_PWM, &t.Z_DIR, &t.Z_EN, {}, 0, 0, 0, 0, 0, 0};
    for (size_t a = 0; a < m.axes.size(); ++a) {
      Slot& s = slot[a];
      s.plant = std::make_unique<AxisPlant>(m.axes[a], m.plant_dt_s);
      s.cpr = m.axes[a].encoder_cpr;
      s.supply_v = m.axes[a].drive.supply_v;
      s.shown = s.plant->encoder_count();
      ++naxes;
    }
    t.CLK = 0;
    t.RX = 1;
    t.BTN_N = 1;
    t.ESTOP = 0;
    t.X_LIM = t.Y_LIM = t.Z_LIM = 0;
    t.HW_A = t.HW_B = 0;
    for (Slot& s : slot) {
      const QuadPins p = quadrature_pins(s.shown, s.plant ? s.cpr : 1 << 30);
      *s.enc_a = p.a;
      *s.enc_b = p.b;
      *s.enc_z = s.plant ? p.z : 0;
    }
    t.eval();
  }
  ~Impl() { top->final(); }

  // Encoder edges of this step: the count the plant reached, at most one
  // edge every other clock (the decoder's rate), the rest carried over.
  void plan_edges() {
    for (int a = 0; a < naxes; ++a) {
      Slot& s = slot[a];
      const int64_t d =
          std::clamp<int64_t>(s.plant->encoder_count() - s.shown, -int64_t(k / 2), int64_t(k / 2));
      s.emit_from = s.shown;
      s.emit_n = d;
      s.shown += d;
    }
  }

  void plant_step(std::vector<uint8_t>& out) {
    plan_edges();
    uint32_t edges_until = 0;  // clocks in which some encoder pin still changes
    for (int a = 0; a < naxes; ++a)
      edges_until = std::max<uint32_t>(edges_until, uint32_t(2 * std::llabs(slot[a].emit_n)));
    Vmotioncore_icebreaker& t = *top;
    bool active = !tx.idle() || rx.busy();
    for (uint32_t c = 0; c < k; ++c) {
      // Pins change only on even clocks while edges are due.
      if (c < edges_until && (c & 1) == 0) {
        for (int a = 0; a < naxes; ++a) {
          Slot& s = slot[a];
          const int64_t n = std::min<int64_t>(std::llabs(s.emit_n), int64_t(c / 2 + 1));
          const QuadPins p = quadrature_pins(s.emit_from + (s.emit_n < 0 ? -n : n), s.cpr);
          *s.enc_a = p.a;
          *s.enc_b = p.b;
          *s.enc_z = p.z;
        }
      }
      t.RX = tx.pin();
      t.CLK = 1;
      t.eval();
      t.CLK = 0;
      t.eval();
      for (int a = 0; a < naxes; ++a) {
        Slot& s = slot[a];
        if (*s.en && *s.pwm) s.drive_sum += *s.dir ? -1 : 1;
      }
      rx.clock(t.TX);
      tx.clock();
    }
    active = active || !tx.idle() || rx.busy() || rx.has_byte();
    while (rx.has_byte()) out.push_back(rx.take());
    for (int a = 0; a < naxes; ++a) {
      Slot& s = slot[a];
      s.plant->step(s.supply_v * double(s.drive_sum) / double(k));
      s.drive_sum = 0;
    }
    cycles += k;
    if (active) last_activity = cycles;
  }

  MachineConfig m;
  uint32_t k;
  int cpb;
  std::unique_ptr<VerilatedContext> ctx;
  std::unique_ptr<Vmotioncore_icebreaker> top;
  Slot slot[kBoardAxes];
  int naxes = 0;
  UartSender tx;
  UartReceiver rx;
  uint64_t cycles = 0, last_activity = 0;
};

VirtualBoard::VirtualBoard(const MachineConfig& m, uint32_t seed) : impl_(std::make_unique<Impl>(m, seed)) {}
VirtualBoard::~VirtualBoard() = default;

void VirtualBoard::send(const uint8_t* p, size_t n) {
  for (size_t i = 0; i < n; ++i) impl_->tx.send(p[i]);
}
size_t VirtualBoard::rx_backlog() const {
  return impl_->tx.queued();
}
void VirtualBoard::run(uint64_t clocks, std::vector<uint8_t>& out) {
  const uint64_t end = impl_->cycles + clocks;
  while (impl_->cycles < end) impl_->plant_step(out);
}
uint64_t VirtualBoard::cycles() const {
  return impl_->cycles;
}
double VirtualBoard::clock_hz() const {
  return impl_->m.clock_hz;
}
uint32_t VirtualBoard::clocks_per_step() const {
  return impl_->k;
}
uint64_t VirtualBoard::link_quiet_clocks() const {
  return impl_->cycles - impl_->last_activity;
}
bool VirtualBoard::dormant() const {
  if (link_quiet_clocks() <= kMaxWatchdogClocks) return false;
  for (const auto& s : impl_->slot)
    if (*s.en || (s.plant && !s.plant->stuck())) return false;
  return true;
}
double VirtualBoard::position_m(int axis) const {
  const auto& s = impl_->slot[axis];
  return s.plant ? s.plant->position_m() : 0;
}
bool VirtualBoard::drive_enabled(int axis) const {
  return *impl_->slot[axis].en;
}
int VirtualBoard::configured_axes() const {
  return impl_->naxes;
}

// ---------------------------------------------------------------------------

Pty::Pty() {
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (master_ < 0) throw std::runtime_error(sys_error("posix_openpt"));
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
    const std::string e = sys_error("grantpt/unlockpt");
    ::close(master_);
    throw std::runtime_error(e);
  }
  const char* name = ::ptsname(master_);
  if (!name) {
    const std::string e = sys_error("ptsname");
    ::close(master_);
    throw std::runtime_error(e);
  }
  path_ = name;
  slave_ = ::open(name, O_RDWR | O_NOCTTY);
  if (slave_ < 0) {
    const std::string e = sys_error(("open " + path_).c_str());
    ::close(master_);
    throw std::runtime_error(e);
  }
  // Raw bytes both ways: no echo, no line editing, no CR/LF mapping.
  termios tio{};
  ::tcgetattr(slave_, &tio);
  ::cfmakeraw(&tio);
  ::tcsetattr(slave_, TCSANOW, &tio);
}

Pty::~Pty() {
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
}

ServeStatus serve(VirtualBoard& board, Pty& pty, const ServeOptions& opt, const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  // The board runs in slices of 100 us: the host's bytes reach the RX line at
  // most that late, well inside the protocol's 1 ms byte timeout.
  const uint64_t slice = std::max<uint64_t>(1, uint64_t(std::llround(100e-6 * board.clock_hz())));
  const int fd = pty.master_fd();
  const auto t0 = Clock::now();
  auto last_host = t0;
  double paused_s = 0;  // wall time spent dormant: the board's clock stood still
  ServeStatus st;
  double last_report_wall = 0, last_report_board = board.board_seconds();
  std::vector<uint8_t> out;
  uint8_t buf[512];

  const auto report = [&](bool force) {
    st.wall_s = seconds_since(t0);
    st.board_s = board.board_seconds();
    const double dw = st.wall_s - last_report_wall;
    if (!force && dw < opt.status_every_s) return;
    if (dw > 0) st.rt_factor = (st.board_s - last_report_board) / dw;
    last_report_wall = st.wall_s;
    last_report_board = st.board_s;
    if (opt.status) opt.status(st);
  };
  const auto take_input = [&] {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) return false;
    board.send(buf, size_t(n));
    st.bytes_in += uint64_t(n);
    last_host = Clock::now();
    return true;
  };

  while (!stop.load()) {
    if (board.rx_backlog() < 64) take_input();
    board.run(slice, out);
    if (!out.empty()) {
      const ssize_t n = ::write(fd, out.data(), out.size());
      const size_t sent = n > 0 ? size_t(n) : 0;
      st.bytes_out += sent;
      st.bytes_dropped += out.size() - sent;
      out.clear();
    }
    if (opt.paced) {
      const double ahead = board.board_seconds() - (seconds_since(t0) - paused_s);
      st.model_bound = ahead < 0;
      if (ahead > 0) std::this_thread::sleep_for(std::chrono::duration<double>(ahead));
    } else {
      st.model_bound = true;
    }
    if (board.dormant() && board.rx_backlog() == 0) {
      st.dormant = true;
      report(true);
      const auto since = Clock::now();
      while (!stop.load()) {
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, 200) > 0 && take_input()) break;
        if (opt.idle_exit_s > 0 && seconds_since(last_host) > opt.idle_exit_s) break;
      }
      paused_s += seconds_since(since);
      st.dormant = false;
      last_report_wall = seconds_since(t0);
      last_report_board = board.board_seconds();
    }
    if (opt.idle_exit_s > 0 && seconds_since(last_host) > opt.idle_exit_s) break;
    report(false);
  }
  st.wall_s = seconds_since(t0);
  st.board_s = board.board_seconds();
  return st;
}

}  // namespace mc::sim
