// The board's link protocol constants and register map: the one source.
// rtl/board_regs.vh and the register table of docs/protocol.md are generated
// from this file (`make regs`, host/gen_board_regs.cpp); the unit test
// test_board_regs fails when either is stale, so edit here and regenerate.
//
// Frame (docs/protocol.md is the spec):
//   SYNC, LEN, SEQ, CMD, payload[LEN], CRC-16 low byte, CRC-16 high byte
// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor)
// over LEN, SEQ, CMD and the payload. Multi-byte fields are little-endian.
#pragma once

#include <array>
#include <cstdint>

namespace mc::board {

// ---- protocol constants -------------------------------------------------
namespace proto {
constexpr uint8_t SYNC = 0xA5;
constexpr uint8_t VERSION = 6;  // 6: HOMED, ORIGIN (machine zero kept on the board); 5: INFO names
                                // the build (step generators, loops, handwheel); 4: machine I/O; 3: POS,
                                // HW_POS read-only, 8-bit error counts
constexpr int HDR_BYTES = 4;    // SYNC, LEN, SEQ, CMD
constexpr int CRC_BYTES = 2;
constexpr int MAX_LEN = 240;           // payload bytes: six segments
constexpr int SEG_BYTES = 40;          // one interpolator segment (10 words)
constexpr int BYTE_TIMEOUT_US = 1000;  // a frame stalled this long is dropped

// Commands (host to board). A reply carries CMD | REPLY.
constexpr uint8_t CMD_PING = 0x00;   // no payload; starts a session (forgets the last sequence number)
constexpr uint8_t CMD_READ = 0x01;   // addr16
constexpr uint8_t CMD_WRITE = 0x02;  // addr16, data32
constexpr uint8_t CMD_SEG = 0x03;    // 1..6 segments, 40 bytes each
constexpr uint8_t REPLY = 0x80;
constexpr uint8_t CMD_TLM = 0xC0;  // board to host, unsolicited: telemetry
constexpr int REPLY_LEN = 5;       // status byte + value32

// Reply status.
constexpr uint8_t ST_OK = 0;
constexpr uint8_t ST_DUP = 1;      // same SEQ as the last applied frame: answered, not applied again
constexpr uint8_t ST_BAD_REG = 2;  // no such register, or not writable
constexpr uint8_t ST_BAD_LEN = 3;  // LEN does not fit the command
constexpr uint8_t ST_BAD_CMD = 4;  // unknown command
constexpr uint8_t ST_FULL = 5;     // segment queue lacks room for the whole frame: not applied
}  // namespace proto

// ---- register map ----------------------------------------------------------
namespace reg {
// PID registers: 0x0000 + hls/pid_regs.hpp address ({axis, reg}), passed through.
constexpr uint16_t PID_BASE = 0x0000;
// Global registers.
constexpr uint16_t ID = 0x0100;
constexpr uint16_t INFO = 0x0101;
constexpr uint16_t CLK_HZ = 0x0102;
constexpr uint16_t BAUD = 0x0103;
constexpr uint16_t STATUS = 0x0104;
constexpr uint16_t FAULT = 0x0105;
constexpr uint16_t CTRL = 0x0106;
constexpr uint16_t WDOG = 0x0107;
constexpr uint16_t SAFETY = 0x0108;
constexpr uint16_t TLM = 0x0109;
constexpr uint16_t LINK_CRC = 0x010A;
constexpr uint16_t LINK_CMD = 0x010B;
constexpr uint16_t LINK_JUNK = 0x010C;
constexpr uint16_t IP_CTRL = 0x010D;
constexpr uint16_t IP_STAT = 0x010E;
constexpr uint16_t IP_SEGS = 0x010F;
constexpr uint16_t IP_SET_X = 0x0110;
constexpr uint16_t IP_SET_Y = 0x0111;
constexpr uint16_t IP_SET_Z = 0x0112;
constexpr uint16_t HW_POS = 0x0113;
constexpr uint16_t HW_CFG = 0x0114;
constexpr uint16_t TLM_HDR = 0x0115;
constexpr uint16_t IO_CTRL = 0x0116;
constexpr uint16_t LATCH = 0x0117;
constexpr uint16_t MPG = 0x0118;
constexpr uint16_t MPG_INC = 0x0119;
constexpr uint16_t STEP_CFG = 0x011A;
constexpr uint16_t IO_STAT = 0x011B;
constexpr uint16_t HOMED = 0x011C;
constexpr uint16_t GLOBAL_END = 0x011D;  // first unused global address (at most 0x0120)
// Per-axis registers: AXIS_BASE + axis * AXIS_STRIDE + offset.
constexpr uint16_t AXIS_BASE = 0x0200;
constexpr uint16_t AXIS_STRIDE = 0x10;
constexpr uint16_t AX_POS = 0x0;
constexpr uint16_t AX_ENC_CFG = 0x1;
constexpr uint16_t AX_IDX = 0x2;
constexpr uint16_t AX_ENC_STAT = 0x3;
constexpr uint16_t AX_CMD = 0x4;
constexpr uint16_t AX_ERR = 0x5;
constexpr uint16_t AX_OUT = 0x6;
constexpr uint16_t AX_DRV = 0x7;
constexpr uint16_t AX_FERR = 0x8;
constexpr uint16_t AX_FOLLOW = 0x9;
constexpr uint16_t AX_ORIGIN = 0xA;
constexpr uint16_t AX_END = 0xB;  // first unused offset

constexpr uint16_t axis(int a, uint16_t off) {
  return uint16_t(AXIS_BASE + a * AXIS_STRIDE + off);
}
}  // namespace reg

// ---- register fields -------------------------------------------------------
namespace bits {
constexpr uint32_t ID_MAGIC = 0x4D430000;  // "MC" in the high half, VERSION in the low
// INFO
constexpr int INFO_NAXES_LSB = 0;      // 4 bits
constexpr int INFO_FIFO_AW_LSB = 4;    // 4 bits
constexpr int INFO_VERSION_LSB = 8;    // 8 bits
constexpr int INFO_STEPPERS_LSB = 16;  // 3 bits: axes built with a step generator (bit a: axis a)
constexpr int INFO_SERVO = 19;         // the PID loops are built (0: a stepper-only board)
constexpr int INFO_HANDWHEEL = 20;     // the handwheel decoder is built
// The INFO fields of a value read from the register.
constexpr int info_naxes(uint32_t info) {
  return int(info >> INFO_NAXES_LSB & 0xFu);
}
constexpr int info_fifo_aw(uint32_t info) {
  return int(info >> INFO_FIFO_AW_LSB & 0xFu);
}
constexpr int info_version(uint32_t info) {
  return int(info >> INFO_VERSION_LSB & 0xFFu);
}
constexpr int info_steppers(uint32_t info) {
  return int(info >> INFO_STEPPERS_LSB & 0x7u);
}
constexpr bool info_servo(uint32_t info) {
  return (info >> INFO_SERVO & 1u) != 0;
}
constexpr bool info_handwheel(uint32_t info) {
  return (info >> INFO_HANDWHEEL & 1u) != 0;
}
// INFO as a board built with these parameters reads it.
constexpr uint32_t info_word(int naxes, int fifo_aw, int version, int steppers, bool servo, bool handwheel) {
  return uint32_t(naxes) << INFO_NAXES_LSB | uint32_t(fifo_aw) << INFO_FIFO_AW_LSB |
         uint32_t(version) << INFO_VERSION_LSB | uint32_t(steppers & 7) << INFO_STEPPERS_LSB |
         uint32_t(servo) << INFO_SERVO | uint32_t(handwheel) << INFO_HANDWHEEL;
}
// STATUS (live)
constexpr int ST_ARMED = 0;
constexpr int ST_ESTOP_IN = 1;
constexpr int ST_IP_BUSY = 2;
constexpr int ST_IP_UNDERRUN = 3;
constexpr int ST_IP_OVF = 4;
constexpr int ST_LIMIT_IN_LSB = 8;  // one bit per axis
constexpr int ST_DRV_EN_LSB = 12;   // one bit per axis
constexpr int ST_PID_EN_LSB = 16;   // one bit per axis
// FAULT (latched; write 1 to clear)
constexpr int F_WDOG = 0;
constexpr int F_ESTOP = 1;
constexpr int F_LIMIT_LSB = 4;  // one bit per axis
constexpr int F_FERR_LSB = 8;   // one bit per axis
constexpr int F_ENC_LSB = 12;   // one bit per axis
// CTRL
constexpr int C_ARM = 0;      // drives may run; cleared by any fault
constexpr int C_IP_HOLD = 1;  // pause the feed
// SAFETY (defaults: every limit and the e-stop enabled, active high)
constexpr int S_LIM_EN_LSB = 0;  // one bit per axis
constexpr int S_ESTOP_EN = 3;
constexpr int S_LIM_INV_LSB = 4;  // one bit per axis: the input trips when low
constexpr int S_ESTOP_INV = 7;
constexpr uint32_t SAFETY_DEFAULT = 0x0F;
// TLM
constexpr int T_DECIM_LSB = 0;  // 16 bits: a frame every DECIM samples, 0 = off
constexpr int T_AXES_LSB = 16;  // 3 bits: axes in the frame
// IP_CTRL (strobes)
constexpr int I_ABORT = 0;
constexpr int I_CLR = 1;
constexpr int I_SET = 2;
// IP_STAT
constexpr int IS_COUNT_LSB = 0;  // words queued, FIFO_AW + 1 bits
constexpr int IS_BUSY = 16;
constexpr int IS_UNDERRUN = 17;
constexpr int IS_OVF = 18;
// HW_CFG, AX_ENC_CFG
constexpr int E_FILT_LSB = 0;  // 8 bits, clocks; the board filters at most 15 (mc_board FILT_W)
constexpr int E_DIR_INV = 8;
constexpr int E_IDX_CLR_EN = 9;
// AX_IDX writes
constexpr int X_ARM = 0;
constexpr int X_DISARM = 1;
// AX_ENC_STAT
constexpr int ES_ERR_CNT_LSB = 0;  // 16 bits
constexpr int ES_ERR = 16;
constexpr int ES_IDX_ARMED = 17;
constexpr int ES_IDX_SEEN = 18;
constexpr int ES_W_ERR_CLR = 0;  // write
// AX_OUT
constexpr int O_U_LSB = 0;  // 16 bits, signed
constexpr int O_SAT = 16;
constexpr int O_PID_EN = 17;
constexpr int O_DRV_EN = 18;
// AX_DRV
constexpr int D_VAL_LSB = 0;  // 16 bits, signed
constexpr int D_OVR = 16;
// IO_CTRL: spindle and coolant (all off while the drives are disarmed)
constexpr int IO_SPINDLE = 0;
constexpr int IO_SPINDLE_REV = 1;
constexpr int IO_FLOOD = 2;
constexpr int IO_MIST = 3;
constexpr int IO_MIST_ON_DIR = 4;  // the spindle-direction pin carries the mist output
constexpr int IO_DUTY_LSB = 16;    // 10 bits: spindle PWM duty, of 1023 (1023: always on)
constexpr int IO_DUTY_BITS = 10;
// LATCH: what latches each axis's position (AX_IDX, armed by AX_IDX.arm)
constexpr int L_SRC_LSB = 0;  // 2 bits per axis
constexpr uint32_t L_SRC_INDEX = 0, L_SRC_HOME = 1, L_SRC_PROBE = 2, L_SRC_NONE = 3;
constexpr int L_PROBE_INV = 8;  // the probe input is active low
constexpr int L_STOP = 9;       // a latch also stops the interpolator and flushes its queue
// MPG: handwheel jog
constexpr int M_ON = 0;
constexpr int M_AXIS_LSB = 1;   // 2 bits
constexpr int M_STEP_LSB = 3;   // 2 bits: counts per detent 1, 10, 100, MPG_INC
constexpr int M_DETENT1 = 5;    // a detent is one count (else four: one quadrature cycle)
constexpr int M_RATE_LSB = 16;  // 8 bits: 16-clock units per count moved (below 2: 2)
constexpr int MPG_MIN_RATE = 2;
constexpr int MPG_INC_BITS = 12;
constexpr int MPG_STEPS[3] = {1, 10, 100};
// STEP_CFG: stepper axes
constexpr int SC_STEPPER_LSB = 0;  // one bit per axis: step/dir on the PWM/DIR pins
constexpr int SC_CLOSED_LSB = 4;   // one bit per axis: POS from the encoder (else the steps sent)
constexpr int SC_PW_LSB = 8;       // 6 bits: step pulse clocks (0: 1); low at least one more
constexpr int SC_SETUP_LSB = 16;   // 6 bits: direction-to-step setup clocks (0: 1)
constexpr int SC_TIME_BITS = 6;
constexpr int SC_STEP_INV_LSB = 24;  // one bit per axis: the step pin pulses low
constexpr int SC_DIR_INV_LSB = 28;   // one bit per axis: the direction pin reversed
// IO_STAT
constexpr int IOS_PROBE = 0;          // probe input, filtered, active high
constexpr int IOS_HOME_LSB = 1;       // one bit per axis: home switches (the limit inputs), filtered
constexpr int IOS_STEP_ERR_LSB = 4;   // one bit per axis: the step generator could not follow
constexpr int IOS_MPG_PEND_LSB = 16;  // 16 bits, signed: handwheel counts still to move
}  // namespace bits

// Reset values of the writable registers (what a read returns before a write).
constexpr uint32_t wdog_default(uint32_t clk_hz) {
  return clk_hz / 10;  // 100 ms
}
constexpr int WDOG_W = 24;  // watchdog period bits, clock cycles

// ---- the table ---------------------------------------------------------------
enum class Access : uint8_t {
  R,    // read-only, live value
  RW,   // written value reads back
  RWL,  // write acts (load, strobe, clear), read gives the live value
};

struct RegDef {
  const char* name;
  uint16_t addr;  // global address, or offset for per-axis registers
  bool per_axis;
  Access access;
  const char* doc;
};

constexpr std::array<RegDef, 40> REGS = {{
    {"ID", reg::ID, false, Access::R, "0x4D43 (\"MC\") << 16 | protocol version"},
    {"INFO", reg::INFO, false, Access::R,
     "[3:0] NAXES, [7:4] FIFO_AW, [15:8] protocol version, [18:16] axes with a step generator, [19] PID "
     "loops built, [20] handwheel built"},
    {"CLK_HZ", reg::CLK_HZ, false, Access::R, "clock frequency, Hz"},
    {"BAUD", reg::BAUD, false, Access::R, "UART rate, bit/s"},
    {"STATUS", reg::STATUS, false, Access::R,
     "[0] armed, [1] e-stop input, [2] interpolator busy, [3] underrun, [4] queue overflow, "
     "[10:8] limit inputs, [14:12] drive enables, [18:16] PID enables"},
    {"FAULT", reg::FAULT, false, Access::RWL,
     "latched faults, write 1 to clear: [0] watchdog, [1] e-stop, [6:4] limit, [10:8] following "
     "error, [14:12] encoder"},
    {"CTRL", reg::CTRL, false, Access::RW, "[0] arm the drives (cleared by a fault), [1] hold the feed"},
    {"WDOG", reg::WDOG, false, Access::RW, "watchdog period, clock cycles [23:0] (reset: CLK_HZ/10)"},
    {"SAFETY", reg::SAFETY, false, Access::RW,
     "[2:0] limit enables, [3] e-stop enable, [6:4] limit active low, [7] e-stop active low (reset 0x0F)"},
    {"TLM", reg::TLM, false, Access::RW, "[15:0] telemetry decimation (0 off), [18:16] axes"},
    {"LINK_CRC", reg::LINK_CRC, false, Access::R,
     "[15:0] frames with a bad CRC, [31:16] framing errors (length, truncated, busy)"},
    {"LINK_CMD", reg::LINK_CMD, false, Access::R, "[15:0] refused frames (NAK), [31:16] duplicates"},
    {"LINK_JUNK", reg::LINK_JUNK, false, Access::R, "[15:0] bytes skipped looking for SYNC"},
    {"IP_CTRL", reg::IP_CTRL, false, Access::RW,
     "strobes: [0] abort, [1] clear flags, [2] set position from IP_SET_X..Z"},
    {"IP_STAT", reg::IP_STAT, false, Access::R,
     "[FIFO_AW:0] words queued, [16] busy, [17] underrun, [18] overflow"},
    {"IP_SEGS", reg::IP_SEGS, false, Access::R, "[15:0] segments completed"},
    {"IP_SET_X", reg::IP_SET_X, false, Access::RW, "position IP_CTRL.set loads, counts"},
    {"IP_SET_Y", reg::IP_SET_Y, false, Access::RW, "position IP_CTRL.set loads, counts"},
    {"IP_SET_Z", reg::IP_SET_Z, false, Access::RW, "position IP_CTRL.set loads, counts"},
    {"HW_POS", reg::HW_POS, false, Access::R, "handwheel position, counts (wraps)"},
    {"HW_CFG", reg::HW_CFG, false, Access::RW, "handwheel [7:0] filter clocks (above 15: 15), [8] reverse"},
    {"TLM_HDR", reg::TLM_HDR, false, Access::R, "[15:0] PID sample count, [31:16] FAULT"},
    {"IO_CTRL", reg::IO_CTRL, false, Access::RW,
     "[0] spindle on, [1] spindle reverse, [2] flood, [3] mist, [4] mist on the spindle-direction pin, "
     "[25:16] spindle PWM duty of 1023; all off while disarmed"},
    {"LATCH", reg::LATCH, false, Access::RW,
     "[1:0], [3:2], [5:4] what latches axis X, Y, Z (AX_IDX): 0 index, 1 home switch, 2 probe, 3 none; "
     "[8] probe active low, [9] a latch stops the interpolator"},
    {"MPG", reg::MPG, false, Access::RW,
     "handwheel jog: [0] on, [2:1] axis, [4:3] counts per detent 1, 10, 100, MPG_INC, [5] one count "
     "per detent (else 4), [23:16] 16-clock units per count moved (at least 2)"},
    {"MPG_INC", reg::MPG_INC, false, Access::RW, "[11:0] counts per detent with MPG step 3"},
    {"STEP_CFG", reg::STEP_CFG, false, Access::RW,
     "[2:0] stepper axes, [6:4] closed loop (POS from the encoder), [13:8] step pulse clocks, "
     "[21:16] direction setup clocks, [26:24] step active low, [30:28] direction reversed"},
    {"IO_STAT", reg::IO_STAT, false, Access::R,
     "[0] probe, [3:1] home switches (filtered, active high), [6:4] step errors, [31:16] handwheel "
     "counts to move (signed)"},
    {"HOMED", reg::HOMED, false, Access::RW,
     "[2:0] axes whose ORIGIN a homing cycle set; the board only keeps it (0 at power-up)"},
    {"POS", reg::AX_POS, true, Access::R,
     "encoder position at the last sample, counts (from power-up; the host keeps offsets)"},
    {"ENC_CFG", reg::AX_ENC_CFG, true, Access::RW,
     "[7:0] filter clocks (above 15: 15), [8] reverse, [9] index clears"},
    {"IDX", reg::AX_IDX, true, Access::RWL, "index position latched, counts; write [0] arm, [1] disarm"},
    {"ENC_STAT", reg::AX_ENC_STAT, true, Access::RWL,
     "[7:0] encoder errors (saturate at 255), [16] error, [17] index armed, [18] index seen; write [0] "
     "clears errors"},
    {"CMD", reg::AX_CMD, true, Access::R, "command at the last sample, counts"},
    {"ERR", reg::AX_ERR, true, Access::R, "PID error at the last sample, counts"},
    {"OUT", reg::AX_OUT, true, Access::R,
     "[15:0] PID output, [16] saturated, [17] PID enabled, [18] drive enabled"},
    {"DRV", reg::AX_DRV, true, Access::RWL,
     "read: [15:0] drive value applied, [16] override on; write: [15:0] value, [16] override"},
    {"FERR", reg::AX_FERR, true, Access::RW, "following-error limit, counts [15:0] (0 off)"},
    {"FOLLOW", reg::AX_FOLLOW, true, Access::R,
     "following error at the last sample, CMD - POS saturated to 32 bits, counts (what FERR checks)"},
    {"ORIGIN", reg::AX_ORIGIN, true, Access::RW,
     "machine zero in POS counts, set by the host's homing cycle; the board only keeps it (0 at power-up)"},
}};

// Telemetry payload: TLM_HDR, then for each axis in TLM.axes (lowest first)
// these registers' values, one 32-bit word each.
constexpr std::array<uint16_t, 4> TLM_AXIS_WORDS = {reg::AX_POS, reg::AX_CMD, reg::AX_ERR, reg::AX_OUT};

}  // namespace mc::board
