// 10,000 lines streamed as fast as Grbl's character-counting protocol
// allows, with status queries throughout: no line lost, doubled or
// reordered, the receive buffer never over 128 bytes, every `?` answered at
// once. Board time only: the dry-run machine is stepped by 1 ms.
#include <gtest/gtest.h>

#include <cstdio>
#include <deque>
#include <random>
#include <string>

#include "tests/grbl_rig.hpp"

namespace mc::grbl::test {
namespace {

constexpr int kLines = 10000;

struct Line {
  std::string text;  // with its '\n'
  gcode::Vec3 end;
};

std::vector<Line> program(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> step(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 9);
  std::vector<Line> v;
  gcode::Vec3 p{};
  for (int n = 1; n <= kLines; ++n) {
    for (size_t i = 0; i < 2; ++i) p[i] = std::round((p[i] + step(rng)) * 1000) / 1000;
    char buf[128];
    const int k = kind(rng);
    if (k == 0)
      std::snprintf(buf, sizeof buf, "N%d G0 X%.3f Y%.3f\n", n, p[0], p[1]);
    else if (k == 1)  // lower case, a comment, spaces: cleaned away
      std::snprintf(buf, sizeof buf, "n%d g1 x%.3f (pass %d) y%.3f f%d ; tail\n", n, p[0], n, p[1],
                    600 + 100 * (n % 40));
    else
      std::snprintf(buf, sizeof buf, "N%dG1X%.3fY%.3fF%d\n", n, p[0], p[1], 600 + 100 * (n % 40));
    v.push_back({buf, p});
  }
  return v;
}

TEST(GrblStream, TenThousandLinesNoneLostDoubledOrReordered) {
  Rig r(test_defaults(), 16);
  const std::vector<Line> prog = program(20261124);
  std::deque<size_t> in_flight;  // bytes of sent, unanswered lines
  size_t in_flight_bytes = 0, next = 0, oks = 0, queries = 0, reports = 0, max_buffered = 0;
  double worst_gap_s = 0, last_report_s = 0;
  std::string pending;  // replies not yet split into lines
  for (int ms = 0; oks < prog.size(); ++ms) {
    ASSERT_LT(ms, 10'000'000) << "stalled after " << oks << " oks";
    // Grbl's character counting: send while the unanswered bytes fit in 128.
    while (next < prog.size() && in_flight_bytes + prog[next].text.size() <= kRxBufferSize) {
      r.engine->receive(prog[next].text);
      in_flight.push_back(prog[next].text.size());
      in_flight_bytes += prog[next].text.size();
      ++next;
    }
    max_buffered = std::max(max_buffered, r.engine->buffered());
    if (ms % 10 == 0) {  // a sender's 10 ms status poll: answered within the same poll
      r.engine->receive("?");
      ++queries;
      const std::string rep = r.engine->take_output();
      ASSERT_EQ(rep.front(), '<') << rep;
      ASSERT_EQ(rep.substr(rep.size() - 3), ">\r\n") << rep;
      ++reports;
      worst_gap_s = std::max(worst_gap_s, r.backend.time_s() - last_report_s);
      last_report_s = r.backend.time_s();
    }
    r.backend.advance(1e-3);
    r.engine->poll();
    pending += r.engine->take_output();
    for (size_t eol; (eol = pending.find("\r\n")) != std::string::npos; pending.erase(0, eol + 2)) {
      const std::string reply = pending.substr(0, eol);
      ASSERT_EQ(reply, "ok") << "line " << oks + 1 << ": " << prog[oks].text;
      ASSERT_FALSE(in_flight.empty());
      in_flight_bytes -= in_flight.front();
      in_flight.pop_front();
      ++oks;
    }
  }
  EXPECT_EQ(oks, size_t(kLines));
  EXPECT_LE(max_buffered, kRxBufferSize);
  EXPECT_EQ(reports, queries);
  // Each line reached the machine once, in order, with its N word.
  const auto& got = r.backend.received();
  ASSERT_EQ(got.size(), size_t(kLines));
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got[i].line_number, int(i + 1));
    ASSERT_EQ(got[i].id, got[0].id + i);
  }
  r.run_until_idle(120);
  EXPECT_EQ(r.backend.status().position, prog.back().end);
  std::printf(
      "streamed %d lines in %.3f s of board time (%.0f lines/s), %zu status reports, "
      "longest gap %.0f ms, receive buffer at most %zu bytes\n",
      kLines, r.backend.time_s(), kLines / r.backend.time_s(), reports, worst_gap_s * 1e3, max_buffered);
}

}  // namespace
}  // namespace mc::grbl::test
