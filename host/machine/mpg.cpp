#include "host/machine/mpg.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"

namespace mc::machine {

namespace br = mc::board::reg;
namespace bb = mc::board::bits;
using mc::host::InputError;
using mc::host::quote;

namespace {

constexpr char kAxes[] = "xyz";
constexpr uint32_t kStepMask = 3u << bb::M_STEP_LSB;
// Samples while following: well inside the board's shortest useful
// watchdog (100 ms by default), and brisk enough to show a turn.
constexpr std::chrono::milliseconds kFollowPoll{20};

// The MPG step field of a step: 0, 1, 2 for 1, 10, 100; -1 for any other.
int step_field(int step) {
  for (int f = 0; f < 3; ++f)
    if (bb::MPG_STEPS[f] == step) return f;
  return -1;
}

}  // namespace

int parse_mpg_step(std::string_view text, std::string_view what) {
  for (int f = 0; f < 3; ++f)
    if (text == std::to_string(bb::MPG_STEPS[f])) return bb::MPG_STEPS[f];
  throw InputError(std::string(what), quote(text), "1, 10 or 100 (board counts a detent)");
}

MpgSetting parse_mpg(std::string_view text, std::string_view what) {
  std::string t(text);
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (t == "off") return {};
  const char* axis = t.empty() ? nullptr : std::strchr(kAxes, t[0]);
  if (!axis || t[0] == '\0')
    throw InputError(std::string(what), quote(text), "off, or an axis and a step: x10, X,100, z 1");
  size_t at = 1;
  if (at < t.size() && (t[at] == ',' || t[at] == ' ')) ++at;
  return {int(axis - kAxes), parse_mpg_step(std::string_view(t).substr(at), what)};
}

std::string mpg_text(const MpgSetting& s) {
  return s.on() ? kAxes[s.axis] + std::to_string(s.step) : "off";
}

double mm_per_detent(const MachineConfig& m, const MpgSetting& s) {
  if (!s.on() || size_t(s.axis) >= m.axes.size()) return 0;
  return double(s.step) / counts_per_m(m.axes[size_t(s.axis)]) * 1e3;
}

uint32_t mpg_rate(const MachineConfig& m, int axis) {
  // Counts come 16 * rate clocks apart, at most: the speed is
  // clock_hz / (16 * rate) counts/s.
  const double max_counts_s = m.axes[size_t(axis)].max_speed_m_s * counts_per_m(m.axes[size_t(axis)]);
  const double rate = std::ceil(m.clock_hz / (16 * max_counts_s));
  return uint32_t(std::clamp(rate, double(bb::MPG_MIN_RATE), 255.0));
}

void set_mpg(mc::host::BoardLink& l, const MachineConfig& m, const MpgSetting& s) {
  uint32_t want = 0;
  if (s.on()) {
    const int naxes = std::min<int>(mc::host::read_naxes(l), int(m.axes.size()));
    if (s.axis >= naxes)
      throw InputError("handwheel axis", std::string(1, kAxes[std::clamp(s.axis, 0, 2)]),
                       "an axis of both the machine (" + m.source + ") and the board: one of " +
                           std::string(kAxes, size_t(naxes)));
    const int f = step_field(s.step);
    if (f < 0)
      throw InputError("handwheel step", std::to_string(s.step), "1, 10 or 100 (board counts a detent)");
    if (!bb::info_handwheel(l.read(br::INFO)))
      throw mc::host::BoardError(
          "the board was built without the handwheel decoder (INFO); build it with HANDWHEEL=1");
    want = 1u << bb::M_ON | uint32_t(s.axis) << bb::M_AXIS_LSB | uint32_t(f) << bb::M_STEP_LSB |
           mpg_rate(m, s.axis) << bb::M_RATE_LSB;
  }
  const uint32_t was = l.read(br::MPG);
  if (was == want) return;
  // The board keeps what is pending across a change of axis: counts turned
  // for X must not move Z. Off first drops them.
  if ((was >> bb::M_ON & 1) && want != 0) l.write(br::MPG, 0);
  l.write_verify(br::MPG, want);
}

MpgSetting read_mpg(mc::host::BoardLink& l) {
  const uint32_t w = l.read(br::MPG);
  if (!(w >> bb::M_ON & 1)) return {};
  const uint32_t f = (w & kStepMask) >> bb::M_STEP_LSB;
  const int step = f < 3 ? bb::MPG_STEPS[f] : int(l.read(br::MPG_INC) & ((1u << bb::MPG_INC_BITS) - 1));
  return {int(w >> bb::M_AXIS_LSB & 3), step};
}

int32_t mpg_pending(mc::host::BoardLink& l) {
  return int16_t(l.read(br::IO_STAT) >> bb::IOS_MPG_PEND_LSB);
}

MpgSample follow_mpg(mc::host::BoardLink& l, int axis, double seconds,
                     const std::function<void(const MpgSample&)>& on_change) {
  using std::chrono::duration;
  const auto t0 = l.now();
  const auto until =
      t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(duration<double>(seconds));
  MpgSample last;
  bool first = true;
  // When the command last moved or counts were pending: the axis settles from there.
  auto still_since = t0;
  for (;;) {
    MpgSample s;
    s.wall_s = duration<double>(l.now() - t0).count();
    s.pending = mpg_pending(l);
    s.cmd = int32_t(l.read(br::axis(axis, br::AX_CMD)));
    s.pos = int32_t(l.read(br::axis(axis, br::AX_POS)));
    const bool moved = first || s.cmd != last.cmd || s.pending != 0;
    if (moved) still_since = l.now();
    if (on_change && (first || s.pending != last.pending || s.cmd != last.cmd || s.pos != last.pos))
      on_change(s);
    first = false;
    last = s;
    const bool in = std::llabs(s.cmd - s.pos) <= mc::host::kInPosition;
    if (l.now() >= until && s.pending == 0 && (in || l.now() - still_since > mc::host::kSettleTimeout))
      return s;
    l.poll(kFollowPoll);
  }
}

}  // namespace mc::machine
