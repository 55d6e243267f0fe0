#include "host/control/jitter_record.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "host/base/errors.hpp"

namespace mc::host {

LatencyStats latency_stats(std::vector<int64_t> ns, int64_t period_ns) {
  LatencyStats s;
  s.samples = ns.size();
  if (ns.empty()) return s;
  std::sort(ns.begin(), ns.end());
  long double sum = 0;
  for (const int64_t v : ns) {
    sum += v;
    s.overruns += v > period_ns;
  }
  const auto rank = [&](double q) {
    const size_t r = size_t(std::ceil(q * double(ns.size())));
    return double(ns[std::min(ns.size(), std::max<size_t>(r, 1)) - 1]) / 1e3;
  };
  s.min_us = double(ns.front()) / 1e3;
  s.max_us = double(ns.back()) / 1e3;
  s.mean_us = double(sum / (long double)ns.size()) / 1e3;
  s.p50_us = rank(0.5);
  s.p99_us = rank(0.99);
  s.p999_us = rank(0.999);
  return s;
}

std::vector<LatencyBin> latency_histogram(const std::vector<int64_t>& ns) {
  constexpr int kFineUs = 100, kPerDecade = 20;
  std::vector<double> edges;
  for (int i = 0; i <= kFineUs; ++i) edges.push_back(i);
  const int64_t mx = ns.empty() ? 0 : *std::max_element(ns.begin(), ns.end());
  // Edges printed with 6 significant digits are the edges: round them now so
  // that the file and the counts agree exactly.
  for (int i = 1; edges.back() * 1e3 <= double(mx); ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", kFineUs * std::pow(10.0, double(i) / kPerDecade));
    edges.push_back(std::strtod(buf, nullptr));
  }
  std::vector<LatencyBin> bins;
  for (size_t i = 0; i + 1 < edges.size(); ++i) bins.push_back({edges[i], edges[i + 1], 0});
  for (const int64_t v : ns) {
    const double us = double(v) / 1e3;
    const auto it = std::upper_bound(edges.begin(), edges.end(), us);
    const size_t b = it == edges.begin() ? 0 : size_t(it - edges.begin()) - 1;
    ++bins[std::min(b, bins.size() - 1)].count;
  }
  return bins;
}

std::string jitter_csv(const std::vector<std::pair<std::string, std::string>>& provenance,
                       const std::vector<LatencyBin>& bins) {
  std::string s;
  for (const auto& [k, v] : provenance) {
    std::string line = v;
    std::replace(line.begin(), line.end(), '\n', ' ');
    s.append("# ").append(k).append(": ").append(line).append("\n");
  }
  s += std::string(kJitterCsvHeader) + "\n";
  for (const LatencyBin& b : bins) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.6g,%.6g,%llu\n", b.lo_us, b.hi_us, (unsigned long long)b.count);
    s += buf;
  }
  return s;
}

namespace {

[[noreturn]] void fail(const std::string& path, const char* doing, int err) {
  throw InputError("--out", quote(path), "a file path in a writable directory",
                   std::string(doing) + ": " + std::strerror(err));
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  std::string tmpl = path_ + ".tmpXXXXXX";
  fd_ = mkstemp(tmpl.data());
  if (fd_ < 0) fail(path_, "cannot create a file there", errno);
  tmp_ = tmpl;
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!tmp_.empty()) ::unlink(tmp_.c_str());
}

void AtomicFile::commit(const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(path_, "write failed", errno);
    done += size_t(n);
  }
  // mkstemp creates 0600; a data file is for everyone to read.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd_, 0666 & ~mask);
  if (::fsync(fd_) != 0) fail(path_, "fsync failed", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(path_, "close failed", errno);
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) fail(path_, "rename failed", errno);
  tmp_.clear();
}

}  // namespace mc::host
