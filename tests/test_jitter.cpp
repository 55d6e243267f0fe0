// The jitter model: the histogram file read back exactly as written, the
// sampler reproducing the histogram (chi-square over bins, KS within a bin),
// determinism per seed, and malformed files rejected with file:line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "host/base/errors.hpp"
#include "host/control/jitter_record.hpp"
#include "sim/plant/jitter.hpp"

namespace mc::sim {
namespace {

using mc::host::InputError;

// A recorder-like sample set: a body near 100 us and a long tail.
std::vector<int64_t> synthetic_lateness(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<int64_t> ns(n);
  for (size_t i = 0; i < n; ++i) {
    const double u = double(rng() >> 11) * 0x1.0p-53;
    // Exponential tail with mean 300 us on top of a 60 us floor.
    ns[i] = 60000 + int64_t(-300000.0 * std::log1p(-u));
  }
  return ns;
}

std::string synthetic_csv(const std::vector<int64_t>& ns) {
  return mc::host::jitter_csv({{"tool", "test"}, {"period_s", "0.01"}}, mc::host::latency_histogram(ns));
}

TEST(Jitter, RecorderOutputParsesBackExactly) {
  const auto ns = synthetic_lateness(20000, 1);
  const auto bins = mc::host::latency_histogram(ns);
  const JitterHistogram h = parse_jitter(synthetic_csv(ns), "mem.csv");
  EXPECT_EQ(h.source, "mem.csv");
  EXPECT_EQ(h.period_s, 0.01);
  EXPECT_EQ(h.get("tool"), "test");
  ASSERT_EQ(h.count.size(), bins.size());
  for (size_t i = 0; i < bins.size(); ++i) {
    EXPECT_EQ(h.count[i], bins[i].count);
    EXPECT_DOUBLE_EQ(h.lo_s[i], bins[i].lo_us * 1e-6);
    EXPECT_DOUBLE_EQ(h.hi_s[i], bins[i].hi_us * 1e-6);
  }
  EXPECT_EQ(h.total(), ns.size());
  // The tail is kept: the largest sample lies in the last bin.
  const double mx = double(*std::max_element(ns.begin(), ns.end())) * 1e-9;
  EXPECT_GE(mx, h.lo_s.back());
  EXPECT_LT(mx, h.hi_s.back());
  // And every sample is counted in the bin that holds it.
  for (const int64_t v : {int64_t(60000), int64_t(99999), int64_t(100000), int64_t(250000)}) {
    const auto one = mc::host::latency_histogram({v});
    for (const auto& b : one) {
      if (b.count) {
        EXPECT_LE(b.lo_us * 1e3, double(v));
        EXPECT_GT(b.hi_us * 1e3, double(v));
      }
    }
  }
}

TEST(Jitter, SamplerReproducesTheHistogram) {
  const JitterHistogram h = parse_jitter(synthetic_csv(synthetic_lateness(50000, 2)), "mem.csv");
  JitterSampler s(h, 42);
  const int n = 1000000;
  std::vector<double> obs(h.count.size(), 0);
  for (int i = 0; i < n; ++i) {
    const double x = s.next_lateness_s();
    // Bins are half-open [lo, hi); a draw is never at hi.
    const size_t b = size_t(std::upper_bound(h.lo_s.begin(), h.lo_s.end(), x) - h.lo_s.begin()) - 1;
    ASSERT_LT(x, h.hi_s[b]);
    obs[b] += 1;
  }
  double chi2 = 0;
  int dof = -1;
  for (size_t b = 0; b < obs.size(); ++b) {
    const double expect = double(n) * double(h.count[b]) / double(h.total());
    if (h.count[b] == 0) {
      EXPECT_EQ(obs[b], 0) << "draw from an empty bin " << b;
      continue;
    }
    chi2 += (obs[b] - expect) * (obs[b] - expect) / expect;
    ++dof;
  }
  // Mean dof, sd sqrt(2 dof): five sd is never reached by chance.
  EXPECT_LT(chi2, dof + 5 * std::sqrt(2.0 * dof)) << "dof " << dof;
}

TEST(Jitter, UniformWithinABin) {
  JitterHistogram h = zero_jitter(0.01);
  h.lo_s = {1e-4};
  h.hi_s = {2e-4};
  JitterSampler s(h, 7);
  const int n = 100000;
  std::vector<double> x(n);
  for (double& v : x) v = (s.next_lateness_s() - 1e-4) / 1e-4;
  std::sort(x.begin(), x.end());
  double d = 0;
  for (int i = 0; i < n; ++i)
    d = std::max({d, std::abs(x[i] - double(i) / n), std::abs(x[i] - double(i + 1) / n)});
  EXPECT_LT(d, 1.63 / std::sqrt(double(n)));  // KS at 1 %
  EXPECT_GE(x.front(), 0.0);
  EXPECT_LT(x.back(), 1.0);
}

TEST(Jitter, DeterministicPerSeedAndSeedsDiffer) {
  const JitterHistogram h = default_jitter();
  JitterSampler a(h, 5), b(h, 5), c(h, 6);
  int differ = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = a.next_lateness_s();
    EXPECT_EQ(x, b.next_lateness_s());
    differ += x != c.next_lateness_s();
  }
  EXPECT_GT(differ, 900);
}

TEST(Jitter, BuiltInHistogramIsTheRecordedOne) {
  const JitterHistogram h = default_jitter();
  EXPECT_EQ(h.period_s, 0.01);
  EXPECT_EQ(std::to_string(h.total()), h.get("samples"));
  EXPECT_FALSE(h.get("kernel").empty());
  EXPECT_FALSE(h.get("virtualization").empty());
}

TEST(Jitter, ZeroJitterSamplesZero) {
  JitterSampler s(zero_jitter(0.01), 1);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(s.next_lateness_s(), 0.0);
}

void expect_rejected(const std::string& text, const std::string& where, const std::string& mentions = "") {
  try {
    parse_jitter(text, "j.csv");
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(where, 0), 0u) << msg;
    EXPECT_NE(msg.find("expected"), std::string::npos) << msg;
    if (!mentions.empty()) {
      EXPECT_NE(msg.find(mentions), std::string::npos) << msg;
    }
  }
}

TEST(Jitter, MalformedFilesNameFileAndLine) {
  const std::string head = "# period_s: 0.01\nlateness_us_lo,lateness_us_hi,count\n";
  expect_rejected(head + "0,1,5\n1,2,x\n", "j.csv:4", "\"1,2,x\"");
  expect_rejected(head + "0,1,5\n1,2\n", "j.csv:4");
  expect_rejected(head + "0,1,5,6\n", "j.csv:3");
  expect_rejected(head + "2,1,5\n", "j.csv:3");
  expect_rejected(head + "-1,1,5\n", "j.csv:3");
  expect_rejected(head + "0,2,5\n1,3,5\n", "j.csv:4", "overlapping");
  expect_rejected(head + "0,1,-5\n", "j.csv:3");
  expect_rejected(head + "0,1,0\n", "j.csv:3", "no samples");
  expect_rejected("# period_s: 0.01\n0,1,5\n", "j.csv:2", "lateness_us_lo");
  expect_rejected("# period_s: abc\n", "j.csv:1", "period_s");
  expect_rejected("# period_s: 0.01\n", "j.csv:1", "header");
  expect_rejected("lateness_us_lo,lateness_us_hi,count\n0,1,5\n", "j.csv", "period_s");
  EXPECT_THROW(load_jitter("/nonexistent/j.csv"), InputError);
  // CRLF and blank lines are fine.
  EXPECT_EQ(
      parse_jitter("# period_s: 0.01\r\n\r\nlateness_us_lo,lateness_us_hi,count\r\n0,1,5\r\n", "j").total(),
      5u);
}

}  // namespace
}  // namespace mc::sim
