#include "host/link/board_regs_gen.hpp"

#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

#include "hls/board_regs.hpp"

namespace mc::host {
namespace {

struct Const {
  std::string name;
  long value;
  int width;  // 0: integer
};

// Every constant the RTL uses, with the Verilog name it gets. The values come
// from the C++ definitions, so only the list of names is written here.
std::vector<Const> constants() {
  using namespace board;
  std::vector<Const> c;
#define P8(n) c.push_back({"P_" #n, long(proto::n), 8})
#define PI(n) c.push_back({"P_" #n, long(proto::n), 0})
  P8(SYNC), P8(VERSION), PI(HDR_BYTES), PI(CRC_BYTES), PI(MAX_LEN), PI(SEG_BYTES), PI(BYTE_TIMEOUT_US);
  P8(CMD_PING), P8(CMD_READ), P8(CMD_WRITE), P8(CMD_SEG), P8(REPLY), P8(CMD_TLM), PI(REPLY_LEN);
  P8(ST_OK), P8(ST_DUP), P8(ST_BAD_REG), P8(ST_BAD_LEN), P8(ST_BAD_CMD), P8(ST_FULL);
#undef P8
#undef PI
  for (const auto& r : REGS)
    c.push_back({std::string(r.per_axis ? "R_AX_" : "R_") + r.name, long(r.addr), r.per_axis ? 4 : 16});
  c.push_back({"R_GLOBAL_END", long(reg::GLOBAL_END), 16});
  // Bit i: the register at global index i (axis offset i) takes writes, or
  // reads back what was written (from the shadow RAM, not a live value).
  long gw = 0, gs = 0, aw = 0, as = 0;
  for (const auto& r : REGS) {
    const long bit = 1L << (r.addr & 0x1F);
    long& w = r.per_axis ? aw : gw;
    long& s = r.per_axis ? as : gs;
    if (r.access != Access::R) w |= bit;
    if (r.access == Access::RW) s |= bit;
  }
  c.push_back({"R_GLOBAL_WMASK", gw, 32});
  c.push_back({"R_GLOBAL_SHADOW", gs, 32});
  c.push_back({"R_AX_WMASK", aw, 16});
  c.push_back({"R_AX_SHADOW", as, 16});
  c.push_back({"R_AXIS_BASE", long(reg::AXIS_BASE), 16});
  c.push_back({"R_AXIS_STRIDE", long(reg::AXIS_STRIDE), 16});
  c.push_back({"R_AX_END", long(reg::AX_END), 4});
#define B(n) c.push_back({"B_" #n, long(bits::n), 0})
  c.push_back({"B_ID_MAGIC", long(bits::ID_MAGIC), 32});
  B(INFO_NAXES_LSB), B(INFO_FIFO_AW_LSB), B(INFO_VERSION_LSB), B(INFO_STEPPERS_LSB), B(INFO_SERVO),
      B(INFO_HANDWHEEL);
  B(ST_ARMED), B(ST_ESTOP_IN), B(ST_IP_BUSY), B(ST_IP_UNDERRUN), B(ST_IP_OVF), B(ST_LIMIT_IN_LSB),
      B(ST_DRV_EN_LSB), B(ST_PID_EN_LSB);
  B(F_WDOG), B(F_ESTOP), B(F_LIMIT_LSB), B(F_FERR_LSB), B(F_ENC_LSB);
  B(C_ARM), B(C_IP_HOLD);
  B(S_LIM_EN_LSB), B(S_ESTOP_EN), B(S_LIM_INV_LSB), B(S_ESTOP_INV);
  c.push_back({"B_SAFETY_DEFAULT", long(bits::SAFETY_DEFAULT), 32});
  B(T_DECIM_LSB), B(T_AXES_LSB);
  B(I_ABORT), B(I_CLR), B(I_SET);
  B(IS_COUNT_LSB), B(IS_BUSY), B(IS_UNDERRUN), B(IS_OVF);
  B(E_FILT_LSB), B(E_DIR_INV), B(E_IDX_CLR_EN);
  B(X_ARM), B(X_DISARM);
  B(ES_ERR_CNT_LSB), B(ES_ERR), B(ES_IDX_ARMED), B(ES_IDX_SEEN), B(ES_W_ERR_CLR);
  B(O_U_LSB), B(O_SAT), B(O_PID_EN), B(O_DRV_EN);
  B(D_VAL_LSB), B(D_OVR);
  B(IO_SPINDLE), B(IO_SPINDLE_REV), B(IO_FLOOD), B(IO_MIST), B(IO_MIST_ON_DIR), B(IO_DUTY_LSB);
  B(L_SRC_LSB), B(L_PROBE_INV), B(L_STOP);
  B(M_ON), B(M_AXIS_LSB), B(M_STEP_LSB), B(M_DETENT1), B(M_RATE_LSB);
  B(SC_STEPPER_LSB), B(SC_CLOSED_LSB), B(SC_PW_LSB), B(SC_SETUP_LSB), B(SC_STEP_INV_LSB), B(SC_DIR_INV_LSB);
  B(IOS_PROBE), B(IOS_HOME_LSB), B(IOS_STEP_ERR_LSB), B(IOS_MPG_PEND_LSB);
#undef B
  c.push_back({"WDOG_W", long(WDOG_W), 0});
  for (size_t i = 0; i < TLM_AXIS_WORDS.size(); ++i)
    c.push_back({"TLM_WORD" + std::to_string(i), long(TLM_AXIS_WORDS[i]), 4});
  c.push_back({"TLM_AXIS_WORDS", long(TLM_AXIS_WORDS.size()), 0});
  return c;
}

const char* access_name(board::Access a) {
  switch (a) {
    case board::Access::R:
      return "R";
    case board::Access::RW:
      return "RW";
    case board::Access::RWL:
      return "RW*";
  }
  return "?";
}

}  // namespace

std::string board_regs_vh() {
  std::ostringstream o;
  o << "// GENERATED from hls/board_regs.hpp by `make regs` (host/board_regs_gen.cpp): do not edit.\n"
       "// Link protocol constants (P_), register addresses (R_; R_AX_ are offsets within an\n"
       "// axis's block) and register fields (B_). docs/protocol.md explains them.\n";
  for (const auto& k : constants()) {
    char buf[160];
    if (k.width == 0)
      std::snprintf(buf, sizeof buf, "localparam integer %s = %ld;\n", k.name.c_str(), k.value);
    else
      std::snprintf(buf, sizeof buf, "localparam [%d:0] %s = %d'h%0*lX;\n", k.width - 1, k.name.c_str(),
                    k.width, (k.width + 3) / 4, k.value);
    o << buf;
  }
  return o.str();
}

std::string board_regs_md() {
  std::ostringstream o;
  o << "| address | name | access | contents |\n|---|---|---|---|\n";
  o << "| 0x0000-0x00FF | PID | RW | pid_core registers, address = {axis, register} (hls/pid_regs.hpp) |\n";
  char buf[64];
  for (const auto& r : board::REGS) {
    if (r.per_axis)
      std::snprintf(buf, sizeof buf, "0x%04X + 0x%02X·a + 0x%X", board::reg::AXIS_BASE,
                    board::reg::AXIS_STRIDE, r.addr);
    else
      std::snprintf(buf, sizeof buf, "0x%04X", r.addr);
    o << "| " << buf << " | " << (r.per_axis ? std::string(r.name) + "[a]" : std::string(r.name)) << " | "
      << access_name(r.access) << " | " << r.doc << " |\n";
  }
  return o.str();
}

}  // namespace mc::host
