// Duration and number parsing for command-line input.
#include <gtest/gtest.h>

#include <string>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"

using namespace mc::host;

namespace {

std::string duration_error(const std::string& text, Zero zero = Zero::reject) {
  try {
    parse_duration(text, "--ts", zero);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ParseDuration, AcceptsSecondsAndUnits) {
  EXPECT_EQ(parse_duration("0.0001"), 1e-4);
  EXPECT_EQ(parse_duration("1e-4"), 1e-4);
  EXPECT_EQ(parse_duration("1E-4"), 1e-4);
  EXPECT_EQ(parse_duration("+1e-4"), 1e-4);
  EXPECT_EQ(parse_duration("2"), 2.0);
  EXPECT_EQ(parse_duration(".5"), 0.5);
  EXPECT_EQ(parse_duration("5."), 5.0);
  EXPECT_EQ(parse_duration("1s"), 1.0);
  EXPECT_EQ(parse_duration("10ms"), 0.01);
  EXPECT_EQ(parse_duration("100us"), 1e-4);
  EXPECT_EQ(parse_duration("10us"), 1e-5);
  EXPECT_EQ(parse_duration("1us"), 1e-6);
  EXPECT_EQ(parse_duration("500ns"), 5e-7);
  EXPECT_EQ(parse_duration("100\xC2\xB5s"), 1e-4);  // MICRO SIGN
  EXPECT_EQ(parse_duration("100\xCE\xBCs"), 1e-4);  // GREEK SMALL LETTER MU
  EXPECT_EQ(parse_duration("2.5 us"), 2.5e-6);
  EXPECT_EQ(parse_duration(" 1ms "), 1e-3);
  // The unit shifts the decimal exponent before conversion, so every spelling of
  // a period gives the same double.
  EXPECT_EQ(parse_duration("0.1ms"), 1e-4);
  EXPECT_EQ(parse_duration("1e2us"), 1e-4);
  EXPECT_EQ(parse_duration("100000ns"), 1e-4);
  EXPECT_EQ(parse_duration("0.3ms"), 3e-4);
  EXPECT_EQ(parse_duration("0", "--tf", Zero::allow), 0.0);
  EXPECT_EQ(parse_duration("0us", "--tf", Zero::allow), 0.0);
  EXPECT_EQ(parse_duration("500us", "--tf", Zero::allow), 5e-4);
}

TEST(ParseDuration, RejectsBadInputQuotingIt) {
  const char* bad[] = {"",    "abc",    "-1",   "-100us",  "0",       "0us",  "0.0", "1e400", "1e-400",
                       "inf", "nan",    "-inf", "100usec", "100 u s", "1ms2", "1e",  "1.2.3", "0x10",
                       "1,5", "10 m s", "ms",   "1 e-3",   "1e-3s5",  "us10", "--1", "1h",    "1min"};
  for (const char* s : bad) {
    const std::string msg = duration_error(s);
    EXPECT_NE(msg, "") << '"' << s << '"';
    EXPECT_EQ(msg.rfind("--ts = \"", 0), 0u) << msg;
    EXPECT_NE(msg.find(std::string("\"") + s + "\""), std::string::npos) << msg;
    EXPECT_NE(msg.find("expected a duration > 0"), std::string::npos) << msg;
  }
  EXPECT_NE(duration_error("-100us").find("negative"), std::string::npos);
  EXPECT_NE(duration_error("0").find(": zero;"), std::string::npos);
  EXPECT_NE(duration_error("abc").find("not a number"), std::string::npos);
  EXPECT_NE(duration_error("100usec").find("unknown unit or trailing characters \"usec\""),
            std::string::npos);
  EXPECT_NE(duration_error("-1", Zero::allow).find("expected a duration >= 0"), std::string::npos);
  // Control characters are escaped: the message stays one line.
  EXPECT_EQ(duration_error("1\nms").find('\n'), std::string::npos);
}

TEST(ParseNumber, StrictDecimal) {
  EXPECT_EQ(parse_number("2"), 2.0);
  EXPECT_EQ(parse_number("-0.5"), -0.5);
  EXPECT_EQ(parse_number("1e-3"), 1e-3);
  EXPECT_EQ(parse_number("+30"), 30.0);
  EXPECT_EQ(parse_number(".05"), 0.05);
  const char* bad[] = {"", "abc", "2x", "inf", "nan", "0x1p3", "1e999", "1..2", "1e", "2 3", "-"};
  for (const char* s : bad) {
    try {
      parse_number(s, "--kp");
      ADD_FAILURE() << "accepted \"" << s << '"';
    } catch (const InputError& e) {
      EXPECT_EQ(e.quantity(), "--kp");
      EXPECT_EQ(e.value(), std::string("\"") + s + "\"");
      EXPECT_NE(e.expected().find("finite decimal number"), std::string::npos);
    }
  }
}

TEST(FormatDuration, PicksAReadableUnit) {
  EXPECT_EQ(format_duration(1e-4), "100 us");
  EXPECT_EQ(format_duration(0.01), "10 ms");
  EXPECT_EQ(format_duration(1), "1 s");
  EXPECT_EQ(format_duration(1e-5), "10 us");
  EXPECT_EQ(format_duration(1e-8), "10 ns");
  EXPECT_EQ(format_duration(0), "0 s");
}
