#include <gtest/gtest.h>

#include "host/gcode/block.hpp"

using mc::gcode::parse_line;

TEST(GcodeParse, Smoke) {
  auto p = parse_line("G1 X1");
  EXPECT_FALSE(p.error);
}
