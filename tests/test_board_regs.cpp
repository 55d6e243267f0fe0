// The register map has one source, hls/board_regs.hpp: rtl/board_regs.vh and
// the table in docs/protocol.md must be exactly what the generator prints
// (regenerate with `make regs`), and the table itself must be consistent.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "hls/board_regs.hpp"
#include "host/link/board_regs_gen.hpp"

namespace mc {
namespace {

std::string slurp(const std::string& rel) {
  std::ifstream in(std::string(MC_SOURCE_DIR) + "/" + rel);
  EXPECT_TRUE(in.good()) << "cannot open " << rel;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(BoardRegs, VerilogIncludeIsGenerated) {
  EXPECT_EQ(slurp("rtl/board_regs.vh"), host::board_regs_vh()) << "rtl/board_regs.vh is stale: run make regs";
}

TEST(BoardRegs, ProtocolDocTableIsGenerated) {
  const std::string doc = slurp("docs/protocol.md");
  const std::string begin = "<!-- GENERATED register table: make regs -->\n",
                    end = "<!-- end of generated table -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), host::board_regs_md())
      << "the register table of docs/protocol.md is stale: run make regs";
}

TEST(BoardRegs, TableIsConsistent) {
  using namespace board;
  std::set<uint16_t> global, axis;
  for (const auto& r : REGS) {
    if (r.per_axis) {
      EXPECT_LT(r.addr, reg::AX_END) << r.name;
      EXPECT_TRUE(axis.insert(r.addr).second) << "duplicate offset " << r.name;
    } else {
      EXPECT_GE(r.addr, reg::ID) << r.name;
      EXPECT_LT(r.addr, reg::GLOBAL_END) << r.name;
      EXPECT_LT(r.addr - reg::ID, 32) << r.name << ": the RTL decodes five bits";
      EXPECT_TRUE(global.insert(r.addr).second) << "duplicate address " << r.name;
    }
  }
  EXPECT_EQ(global.size(), size_t(reg::GLOBAL_END - reg::ID)) << "a hole in the global block";
  EXPECT_EQ(axis.size(), size_t(reg::AX_END)) << "a hole in the axis block";
  // The telemetry words are per-axis registers that exist.
  for (uint16_t w : TLM_AXIS_WORDS) EXPECT_TRUE(axis.count(w));
  // A frame of whole segments fits MAX_LEN, and a telemetry frame of three
  // axes fits link_tx's RAM (16 words, word 0 the reply's).
  EXPECT_EQ(proto::MAX_LEN % proto::SEG_BYTES, 0);
  EXPECT_LE(1 + 3 * int(TLM_AXIS_WORDS.size()), 15);
}

}  // namespace
}  // namespace mc
