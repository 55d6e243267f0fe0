// The wake-up jitter of a host loop: a histogram measured on a real machine
// (`motionctl jitter`, format in host/jitter_record.hpp) and a sampler that
// draws lateness from it, deterministic for a seed on every platform.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace mc::sim {

struct JitterHistogram {
  std::string source;                   // file name, for messages and reports
  std::vector<std::string> provenance;  // the '#' lines, without "# "
  double period_s = 0;                  // the loop period it was measured at
  std::vector<double> lo_s, hi_s;       // bin edges, seconds; contiguous or gapped, increasing
  std::vector<uint64_t> count;

  uint64_t total() const;
  // A provenance value by key ("kernel", "lateness_us_p99", ...), "" if absent.
  std::string get(std::string_view key) const;
};

// Throw mc::host::InputError naming "file:line", quoting the line and saying
// what was expected there.
JitterHistogram load_jitter(const std::string& path);
JitterHistogram parse_jitter(std::string_view text, const std::string& source);
// configs/jitter/linux_10ms.csv, embedded at build time.
JitterHistogram default_jitter();
// Every wake on time: one bin [0, 0]. For tests and for "no jitter" runs.
JitterHistogram zero_jitter(double period_s);

// Inverse CDF over the bins (a bin by its count), then uniform within the
// bin. Doubles come from the raw 64-bit engine output, not from
// std::uniform_real_distribution (implementation-defined), so a seed gives
// the same sequence with any standard library.
class JitterSampler {
 public:
  // Throws InputError for a histogram with no samples.
  JitterSampler(const JitterHistogram& h, uint64_t seed);
  double next_lateness_s();

 private:
  std::vector<double> lo_, hi_;
  std::vector<uint64_t> cum_;  // cumulative counts, non-empty bins only
  std::mt19937_64 rng_;
};

}  // namespace mc::sim
