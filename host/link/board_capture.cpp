#include "host/link/board_capture.hpp"

#include <signal.h>

#include <atomic>
#include <cmath>

#include "host/base/errors.hpp"
#include "host/link/protocol.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

namespace {
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");
extern "C" void on_interrupt(int) {
  g_interrupted.store(true);
}
}  // namespace

const std::atomic<bool>& interrupt_requested() {
  return g_interrupted;
}

void catch_interrupts() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

double board_tx_seconds(int bytes, int frames, double clk_hz, double baud) {
  if (!(clk_hz > 0) || !(baud > 0)) throw InputError("clock / baud", "not above 0", "positive values");
  const double clocks_per_bit = std::floor(clk_hz / baud + 0.5);  // uart_tx's DIV
  return (double(bytes) * (10 * clocks_per_bit + 2) + 32.0 * frames) / clk_hz;
}

uint32_t telemetry_decimation(double ts_s, double clk_hz, double baud, int replies, int axes) {
  if (!(ts_s > 0)) throw InputError("sample period", "not above 0", "a positive value");
  const double busy_s =
      board_tx_seconds(telemetry_frame_bytes(axes) + replies * kReplyBytes, 1 + replies, clk_hz, baud);
  return uint32_t(std::max(1.0, std::ceil(busy_s / ts_s - 1e-9)));
}

uint32_t telemetry_decimation(BoardLink& l, double ts_s, int replies, int axes) {
  return telemetry_decimation(ts_s, double(l.read(br::CLK_HZ)), double(l.read(br::BAUD)), replies, axes);
}

bool TelemetryUnwrap::take(const proto::Frame& f, proto::Telemetry& t, int64_t& n) {
  try {
    t = proto::parse_telemetry(f, mask_);
  } catch (const InputError&) {
    return false;  // a frame of an earlier TLM setting
  }
  if (!have_) {
    n = t.sample;
    have_ = true;
  } else {
    const int64_t d = int64_t(uint16_t(t.sample - uint16_t(last_)));
    n = last_ + d;
    if (d != int64_t(decim_)) {
      ++gaps_;
      missing_ += std::max<int64_t>(0, d / int64_t(decim_) - 1);
    }
  }
  last_ = n;
  return true;
}

TelemetryStream::TelemetryStream(BoardLink& l, int axis, uint32_t decim, int64_t ping_every)
    : l_(l), decim_(decim), ping_every_(std::max<int64_t>(1, ping_every)), unwrap_(1u << axis, decim) {
  l_.write(br::TLM, 0);
  l_.telemetry().clear();
  l_.write(br::TLM, decim << bb::T_DECIM_LSB | (1u << axis) << bb::T_AXES_LSB);
}

TelemetryStream::~TelemetryStream() {
  try {
    l_.write(br::TLM, 0);
    l_.telemetry().clear();
  } catch (...) {  // the link is gone: the watchdog turns the drives off anyway
  }
}

size_t TelemetryStream::next(std::vector<TlmSample>& out) {
  using Clock = std::chrono::steady_clock;
  auto quiet_since = Clock::now();
  size_t added = 0;
  while (added == 0) {
    if (g_interrupted.load())
      throw Interrupted(
          "interrupted; the command's temporary settings (telemetry, experiment gains, drive override) are "
          "undone");
    l_.poll(std::chrono::milliseconds(20));
    auto& q = l_.telemetry();
    while (!q.empty()) {
      const proto::Frame f = std::move(q.front());
      q.pop_front();
      proto::Telemetry t;
      TlmSample s;
      const bool first = !unwrap_.started();
      if (!unwrap_.take(f, t, s.n)) continue;
      if (first) last_ping_ = s.n;
      const proto::AxisSample& a = t.axes.at(0);
      s.pos = a.pos;
      s.cmd = a.cmd;
      s.err = a.err;
      s.u = a.u;
      s.fault = t.fault;
      out.push_back(s);
      ++added;
    }
    const auto now = Clock::now();
    if (added) quiet_since = now;
    if ((unwrap_.started() && unwrap_.last() - last_ping_ >= ping_every_) ||
        now - quiet_since > std::chrono::milliseconds(100)) {
      l_.transact(proto::ping(0));  // throws when the board no longer answers
      last_ping_ = unwrap_.last();
      quiet_since = now;
    }
  }
  return added;
}

}  // namespace mc::host
