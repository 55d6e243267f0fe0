#include "host/link/board_state.hpp"

#include <algorithm>

#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

bool BoardState::armed() const {
  return status & (1u << bb::ST_ARMED);
}

int read_naxes(BoardLink& l) {
  return bb::info_naxes(l.read(br::INFO));
}

std::string build_text(uint32_t info) {
  std::string t = bb::info_servo(info) ? "servo loops; " : "no loops; ";
  std::string st;
  for (int a = 0; a < bb::info_naxes(info) && a < 3; ++a)
    if (bb::info_steppers(info) >> a & 1) st += (st.empty() ? "" : ", ") + std::string(1, "xyz"[a]);
  t += st.empty() ? "no step generators" : "step generators on " + st;
  t += bb::info_handwheel(info) ? "; handwheel" : "; no handwheel";
  return t;
}

std::string fault_names(uint32_t f) {
  std::string s;
  const auto add = [&](const std::string& n) { s += (s.empty() ? "" : ", ") + n; };
  if (f & (1u << bb::F_WDOG)) add("watchdog");
  if (f & (1u << bb::F_ESTOP)) add("e-stop");
  static const char* const ax[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (f & (1u << (bb::F_LIMIT_LSB + a))) add(std::string("limit ") + ax[a]);
    if (f & (1u << (bb::F_FERR_LSB + a))) add(std::string("following error ") + ax[a]);
    if (f & (1u << (bb::F_ENC_LSB + a))) add(std::string("encoder ") + ax[a]);
  }
  return s.empty() ? "none" : s;
}

uint32_t read_ts_cycles(BoardLink& l) {
  const uint32_t ts = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS));
  const uint32_t lat = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_LATENCY));
  return std::max(ts, lat);
}

BoardState read_state(BoardLink& l) {
  BoardState s;
  s.id = l.read(br::ID);
  s.naxes = read_naxes(l);
  s.clk_hz = l.read(br::CLK_HZ);
  s.ts_cycles = read_ts_cycles(l);
  s.wdog = l.read(br::WDOG);
  s.status = l.read(br::STATUS);
  s.fault = l.read(br::FAULT);
  s.ip_stat = l.read(br::IP_STAT);
  s.ip_segs = l.read(br::IP_SEGS);
  s.link_crc = l.read(br::LINK_CRC);
  s.link_cmd = l.read(br::LINK_CMD);
  s.link_junk = l.read(br::LINK_JUNK);
  for (int a = 0; a < s.naxes; ++a) {
    AxisState x;
    x.pos = int32_t(l.read(br::axis(a, br::AX_POS)));
    x.cmd = int32_t(l.read(br::axis(a, br::AX_CMD)));
    x.err = int32_t(l.read(br::axis(a, br::AX_ERR)));
    const uint32_t out = l.read(br::axis(a, br::AX_OUT));
    x.u = int16_t(out & 0xFFFF);
    x.sat = out >> bb::O_SAT & 1;
    x.pid_en = out >> bb::O_PID_EN & 1;
    x.drv_en = out >> bb::O_DRV_EN & 1;
    s.axes.push_back(x);
  }
  return s;
}

void set_position(BoardLink& l, const std::vector<std::pair<int, int32_t>>& axes) {
  for (const auto& [a, pos] : axes) l.write(uint16_t(br::IP_SET_X + a), uint32_t(pos));
  l.write(br::IP_CTRL, 1u << bb::I_SET);
}

std::array<int64_t, 3> arm(BoardLink& l, const Note& note) {
  const int naxes = read_naxes(l);
  std::array<int64_t, 3> at{};
  const bool armed = l.read(br::STATUS) & (1u << bb::ST_ARMED);
  if (!armed) {
    const uint32_t fault = l.read(br::FAULT);
    if (fault == (1u << bb::F_WDOG)) {
      if (note)
        note("clearing the watchdog fault: the drives went off when the last command's link went quiet");
      l.write(br::FAULT, fault);
    } else if (fault != 0) {
      throw BoardError("fault latched: " + fault_names(fault) +
                       "; remove its cause, then run 'motionctl clear-fault'");
    }
    // The command starts where the axes are: nothing left over runs on,
    // the spindle and coolant included.
    l.write(br::IP_CTRL, 1u << bb::I_ABORT | 1u << bb::I_CLR);
    l.write(br::IO_CTRL, 0);
    std::vector<std::pair<int, int32_t>> here;
    for (int a = 0; a < naxes; ++a) {
      here.emplace_back(a, int32_t(l.read(br::axis(a, br::AX_POS))));
      at[size_t(a)] = here.back().second;
    }
    set_position(l, here);
    l.write(br::CTRL, 1u << bb::C_ARM);
    if (!(l.read(br::STATUS) & (1u << bb::ST_ARMED)))
      throw BoardError("the board did not arm (FAULT: " + fault_names(l.read(br::FAULT)) + ")");
  } else {
    for (int a = 0; a < naxes; ++a) at[size_t(a)] = int32_t(l.read(br::axis(a, br::AX_CMD)));
  }
  return at;
}

std::array<int64_t, 3> abort_interpolator(BoardLink& l) {
  l.write(br::IP_CTRL, 1u << bb::I_ABORT | 1u << bb::I_CLR);
  const int naxes = std::min(read_naxes(l), 3);
  // Read until two rounds agree: the first may still show the sample before.
  std::array<int64_t, 3> at{}, before{};
  for (int round = 0; round < 8; ++round) {
    for (int a = 0; a < naxes; ++a) at[size_t(a)] = int32_t(l.read(br::axis(a, br::AX_CMD)));
    if (round > 0 && at == before) break;
    before = at;
  }
  return at;
}

std::array<int64_t, 3> start_position(BoardLink& l) {
  const int naxes = read_naxes(l);
  const bool armed = l.read(br::STATUS) & (1u << bb::ST_ARMED);
  std::array<int64_t, 3> at{};
  for (int a = 0; a < naxes && a < 3; ++a)
    at[size_t(a)] = int32_t(l.read(br::axis(a, armed ? br::AX_CMD : br::AX_POS)));
  return at;
}

MachineOrigin read_origin(BoardLink& l) {
  MachineOrigin o;
  const int naxes = std::min(read_naxes(l), 3);
  o.homed = l.read(br::HOMED) & ((1u << naxes) - 1);
  for (int a = 0; a < naxes; ++a) o.counts[size_t(a)] = int32_t(l.read(br::axis(a, br::AX_ORIGIN)));
  return o;
}

void write_origin(BoardLink& l, int a, int64_t counts) {
  const uint16_t reg = br::axis(a, br::AX_ORIGIN);
  l.write(reg, uint32_t(int32_t(counts)));
  const uint32_t homed = l.read(br::HOMED) | 1u << a;
  l.write(br::HOMED, homed);
  if (int32_t(l.read(reg)) != counts || l.read(br::HOMED) != homed)
    throw BoardError("ORIGIN of axis " + std::to_string(a) + " did not read back " + std::to_string(counts));
}

void clear_homed(BoardLink& l, uint32_t mask) {
  l.write(br::HOMED, l.read(br::HOMED) & ~mask);
}

namespace {
std::string letter(int a) {
  return a >= 0 && a < 3 ? std::string(1, "xyz"[a]) : std::to_string(a);
}
}  // namespace

void require_gains(BoardLink& l, int a) {
  if (l.read(pid_reg::addr(uint8_t(a), pid_reg::KP)) == 0 &&
      l.read(pid_reg::addr(uint8_t(a), pid_reg::KI)) == 0)
    throw InputError("axis " + letter(a), "Kp = Ki = 0",
                     "gains first: 'motionctl gains set --axis " + letter(a) +
                         " --defaults' or 'motionctl config load FILE'");
}

void require_enabled(BoardLink& l, int a) {
  if (!(l.read(pid_reg::addr(uint8_t(a), pid_reg::CTRL)) & 1))
    throw InputError("axis " + letter(a), "disabled",
                     "an enabled axis: run 'motionctl enable --axis " + letter(a) + "' first");
}

std::array<int64_t, 3> enable_axes(BoardLink& l, const std::vector<int>& axes, const Note& note) {
  for (int a : axes) require_gains(l, a);
  const std::array<int64_t, 3> at = arm(l, note);
  for (int a : axes) l.write_verify(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1, 1);
  return at;
}

void disable_axes(BoardLink& l, const std::vector<int>& axes, bool drives_off) {
  if (drives_off) l.write(br::CTRL, 0);
  for (int a : axes) l.write_verify(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 0, 1);
}

uint32_t clear_faults(BoardLink& l) {
  const uint32_t f = l.read(br::FAULT);
  if (f != 0) {
    l.write(br::FAULT, f);
    const uint32_t still = l.read(br::FAULT);
    if (still) throw BoardError("fault still latched, its cause is present: " + fault_names(still));
  }
  return f;
}

}  // namespace mc::host
