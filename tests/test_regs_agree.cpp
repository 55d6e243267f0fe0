// The Verilog includes mirror the C++ headers: parse every localparam in
// rtl/mc_fixed.vh and rtl/pid_regs.vh and compare with the C++ constants.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <string>

#include "hls/interp_seg.hpp"
#include "hls/mc_fixed.hpp"
#include "hls/pid_regs.hpp"

namespace mc {
namespace {

std::map<std::string, long> parse_vh(const std::string& file) {
  std::ifstream in(std::string(MC_RTL_DIR) + "/" + file);
  EXPECT_TRUE(in.good()) << "cannot open rtl/" << file;
  std::map<std::string, long> out;
  const std::regex re(
      R"(localparam\s+(?:integer|\[[^\]]*\])\s+(\w+)\s*=\s*(?:\d+'h([0-9A-Fa-f]+)|(\d+))\s*;)");
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, re))
      out[m[1]] = m[2].matched ? std::stol(m[2], nullptr, 16) : std::stol(m[3]);
  }
  return out;
}

TEST(RegsAgree, FixedPointWidths) {
  auto v = parse_vh("mc_fixed.vh");
  const std::map<std::string, long> cpp = {{"MC_POS_W", POS_W},       {"MC_OUT_W", OUT_W},
                                           {"MC_ACC_W", ACC_W},       {"MC_ACC_FRAC", ACC_FRAC},
                                           {"MC_COEF_M_W", COEF_M_W}, {"MC_COEF_S_W", COEF_S_W},
                                           {"MC_MUL_X_W", MUL_X_W},   {"MC_D_OPER_FRAC", D_OPER_FRAC}};
  EXPECT_EQ(v.size(), cpp.size()) << "a width was added on one side only";
  for (const auto& [k, val] : cpp) EXPECT_EQ(v[k], val) << k;
}

TEST(RegsAgree, PidRegisterAddresses) {
  using namespace pid_reg;
  auto v = parse_vh("pid_regs.vh");
  const std::map<std::string, long> cpp = {{"PID_REG_KP", KP},
                                           {"PID_REG_KI", KI},
                                           {"PID_REG_KD_A", KD_A},
                                           {"PID_REG_KD_B", KD_B},
                                           {"PID_REG_KF1", KF1},
                                           {"PID_REG_KF2", KF2},
                                           {"PID_REG_ILIM", ILIM},
                                           {"PID_REG_OLIM", OLIM},
                                           {"PID_REG_DBAND", DBAND},
                                           {"PID_REG_ELIM", ELIM},
                                           {"PID_REG_CTRL", CTRL},
                                           {"PID_NREGS_RAM", NREGS_RAM},
                                           {"PID_GLOBAL_AXIS", GLOBAL_AXIS},
                                           {"PID_G_TS", G_TS},
                                           {"PID_G_LATENCY", G_LATENCY},
                                           {"PID_G_NAXES", G_NAXES}};
  EXPECT_EQ(v.size(), cpp.size()) << "a register was added on one side only";
  for (const auto& [k, val] : cpp) EXPECT_EQ(v[k], val) << k;
}

TEST(RegsAgree, InterpolatorSegmentFormat) {
  using namespace seg;
  auto v = parse_vh("interp_seg.vh");
  const std::map<std::string, long> cpp = {{"SEG_WORDS", SEG_WORDS},
                                           {"SEG_PH_W", PH_W},
                                           {"SEG_N_W", N_W},
                                           {"SEG_ARC_W", ARC_W},
                                           {"SEG_D_W", D_W},
                                           {"SEG_TICK_LOG2", TICK_LOG2},
                                           {"SEG_W_HDR", W_HDR},
                                           {"SEG_W_N", W_N},
                                           {"SEG_W_INC_LO", W_INC_LO},
                                           {"SEG_W_INC_HI", W_INC_HI},
                                           {"SEG_W_A", W_A},
                                           {"SEG_W_B", W_B},
                                           {"SEG_W_C", W_C},
                                           {"SEG_W_D", W_D},
                                           {"SEG_W_E", W_E},
                                           {"SEG_W_K_LO", W_K_LO},
                                           {"SEG_T_LINE", T_LINE},
                                           {"SEG_T_ARC", T_ARC},
                                           {"SEG_T_DWELL", T_DWELL},
                                           {"SEG_H_TYPE_LSB", H_TYPE_LSB},
                                           {"SEG_H_LAST", H_LAST},
                                           {"SEG_H_CCW", H_CCW},
                                           {"SEG_H_PLANE_LSB", H_PLANE_LSB},
                                           {"SEG_H_NQ_LSB", H_NQ_LSB},
                                           {"SEG_H_NEG_LSB", H_NEG_LSB}};
  EXPECT_EQ(v.size(), cpp.size()) << "a constant was added on one side only";
  for (const auto& [k, val] : cpp) EXPECT_EQ(v[k], val) << k;
}

}  // namespace
}  // namespace mc
