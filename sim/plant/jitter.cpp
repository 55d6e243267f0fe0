#include "sim/plant/jitter.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "host/base/errors.hpp"
#include "host/control/jitter_record.hpp"
#include "jitter_default.hpp"  // generated: kDefaultJitterCsv

namespace mc::sim {
namespace {

using mc::host::InputError;
using mc::host::quote;

__extension__ typedef unsigned __int128 u128;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  return s;
}

bool parse_double(std::string_view s, double& v) {
  s = trim(s);
  if (s.empty()) return false;
  // strtod needs a terminated string; fields are short.
  const std::string str(s);
  char* end = nullptr;
  v = std::strtod(str.c_str(), &end);
  return end == str.c_str() + str.size() && std::isfinite(v);
}

bool parse_u64(std::string_view s, uint64_t& v) {
  s = trim(s);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

}  // namespace

uint64_t JitterHistogram::total() const {
  uint64_t t = 0;
  for (const uint64_t c : count) t += c;
  return t;
}

std::string JitterHistogram::get(std::string_view key) const {
  for (const std::string& p : provenance) {
    if (p.size() > key.size() && p.compare(0, key.size(), key) == 0 && p[key.size()] == ':') {
      return std::string(trim(std::string_view(p).substr(key.size() + 1)));
    }
  }
  return "";
}

JitterHistogram parse_jitter(std::string_view text, const std::string& source) {
  JitterHistogram h;
  h.source = source;
  bool header = false;
  int line_no = 0, period_line = 0;
  const auto where = [&](int n) { return source + ":" + std::to_string(n); };
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t nl = std::min(text.find('\n', pos), text.size());
    const std::string_view raw = text.substr(pos, nl - pos);
    const std::string_view line = trim(raw);
    pos = nl + 1;
    ++line_no;
    if (line.empty()) continue;
    if (!header) {
      if (line[0] == '#') {
        std::string_view p = line.substr(1);
        if (!p.empty() && p[0] == ' ') p.remove_prefix(1);
        h.provenance.emplace_back(p);
        if (p.rfind("period_s:", 0) == 0) {
          if (!parse_double(p.substr(9), h.period_s) || !(h.period_s > 0)) {
            throw InputError(where(line_no), quote(line), "\"# period_s: SECONDS\" with a number > 0");
          }
          period_line = line_no;
        }
      } else if (line == mc::host::kJitterCsvHeader) {
        header = true;
      } else {
        throw InputError(where(line_no), quote(line),
                         std::string("a '#' provenance line or the header ") + mc::host::kJitterCsvHeader);
      }
      continue;
    }
    // lo,hi,count
    const size_t c1 = line.find(','), c2 = c1 == std::string_view::npos ? c1 : line.find(',', c1 + 1);
    double lo = 0, hi = 0;
    uint64_t n = 0;
    const char* expected = "a row lo_us,hi_us,count: 0 <= lo <= hi, count a non-negative integer";
    if (c2 == std::string_view::npos || line.find(',', c2 + 1) != std::string_view::npos ||
        !parse_double(line.substr(0, c1), lo) || !parse_double(line.substr(c1 + 1, c2 - c1 - 1), hi) ||
        !parse_u64(line.substr(c2 + 1), n) || lo < 0 || hi < lo) {
      throw InputError(where(line_no), quote(line), expected);
    }
    if (!h.hi_s.empty() && lo * 1e-6 < h.hi_s.back()) {
      throw InputError(where(line_no), quote(line), "bins in increasing order, not overlapping",
                       "starts before the previous bin ends");
    }
    h.lo_s.push_back(lo * 1e-6);
    h.hi_s.push_back(hi * 1e-6);
    h.count.push_back(n);
  }
  if (!header) {
    throw InputError(where(line_no), "end of file", std::string("the header ") + mc::host::kJitterCsvHeader);
  }
  if (period_line == 0) {
    throw InputError(source, "no period", "a line \"# period_s: SECONDS\" before the header");
  }
  if (h.total() == 0) throw InputError(where(line_no), "no samples", "bins with a total count > 0");
  return h;
}

JitterHistogram load_jitter(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError("jitter histogram", quote(path), "a readable file", "cannot open");
  std::ostringstream ss;
  ss << f.rdbuf();
  return parse_jitter(ss.str(), path);
}

JitterHistogram default_jitter() {
  return parse_jitter(kDefaultJitterCsv, "configs/jitter/linux_10ms.csv (built in)");
}

JitterHistogram zero_jitter(double period_s) {
  JitterHistogram h;
  h.source = "zero jitter";
  h.period_s = period_s;
  h.lo_s = {0};
  h.hi_s = {0};
  h.count = {1};
  return h;
}

JitterSampler::JitterSampler(const JitterHistogram& h, uint64_t seed) : rng_(seed) {
  uint64_t c = 0;
  for (size_t i = 0; i < h.count.size(); ++i) {
    if (h.count[i] == 0) continue;
    c += h.count[i];
    cum_.push_back(c);
    lo_.push_back(h.lo_s[i]);
    hi_.push_back(h.hi_s[i]);
  }
  if (c == 0) throw InputError("jitter histogram " + h.source, "no samples", "bins with a total count > 0");
}

double JitterSampler::next_lateness_s() {
  // Sample index in [0, total): the high word of a 64x64 product (no modulo bias to speak of).
  const uint64_t k = uint64_t((u128(rng_()) * cum_.back()) >> 64);
  const size_t b = size_t(std::upper_bound(cum_.begin(), cum_.end(), k) - cum_.begin());
  // Uniform in [0, 1) from the top 53 bits.
  const double u = double(rng_() >> 11) * 0x1.0p-53;
  return lo_[b] + (hi_[b] - lo_[b]) * u;
}

}  // namespace mc::sim
