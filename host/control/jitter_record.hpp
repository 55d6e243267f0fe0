// Wake-up lateness of a periodic loop on this machine: the statistics and the
// histogram file that `motionctl jitter` writes and the co-simulation's host
// loop draws its jitter from (sim/jitter.hpp reads it).
//
// File format (CSV, '#' lines first):
//   # key: value            provenance and summary, one per line; period_s is
//                           required by the reader, the rest is for people
//   lateness_us_lo,lateness_us_hi,count
//   0,1,17                  bins in microseconds, contiguous, increasing
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace mc::host {

constexpr const char* kJitterCsvHeader = "lateness_us_lo,lateness_us_hi,count";

struct LatencyStats {
  uint64_t samples = 0;
  uint64_t overruns = 0;  // wakes later than one full period after their deadline
  double min_us = 0, mean_us = 0, p50_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
};

// Percentiles by nearest rank on the exact samples. Empty input: all zero.
LatencyStats latency_stats(std::vector<int64_t> lateness_ns, int64_t period_ns);

struct LatencyBin {
  double lo_us, hi_us;
  uint64_t count;
};

// 1 us bins from 0 to 100 us, then 20 logarithmic bins per decade until the
// largest sample is inside (the tail is kept, at about 12 % resolution).
// A sample exactly on an edge goes into the bin above it; negative samples
// (a clock that cannot go back makes them impossible) into the first bin.
std::vector<LatencyBin> latency_histogram(const std::vector<int64_t>& lateness_ns);

// The whole file: "# key: value" lines, the header, the bins.
std::string jitter_csv(const std::vector<std::pair<std::string, std::string>>& provenance,
                       const std::vector<LatencyBin>& bins);

// Writes `text` to `path` through a temporary file in the same directory and
// a rename, so that a reader never sees a partial file and a failure leaves
// nothing behind. Open the temporary early (before long work) to fail fast.
class AtomicFile {
 public:
  // Throws InputError naming the path when the directory is not writable.
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  // Writes, flushes, renames. Throws InputError naming the path on failure.
  void commit(const std::string& text);
  const std::string& path() const { return path_; }

 private:
  std::string path_, tmp_;
  int fd_ = -1;
};

}  // namespace mc::host
