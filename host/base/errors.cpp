#include "host/base/errors.hpp"

#include <cstdio>

namespace mc::host {

std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

namespace {

// The length of the valid UTF-8 sequence at s[i] (0: not one), so that "µs"
// stays readable while stray bytes of a binary file are escaped.
size_t utf8_length(std::string_view s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  const size_t n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k)
    if ((b(i + k) & 0xC0) != 0x80) return 0;
  return n;
}

}  // namespace

std::string quote(std::string_view text) {
  // A message is one line a person reads: a long value (a whole binary
  // file read as one "line") is cut, and says how long it was.
  constexpr size_t kShown = 200;
  const std::string_view shown = text.substr(0, kShown);
  std::string s = "\"";
  for (size_t i = 0; i < shown.size(); ++i) {
    const char c = shown[i];
    const auto u = static_cast<unsigned char>(c);
    const size_t n = u >= 0x80 ? utf8_length(shown, i) : 1;
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (u < 0x20 || u == 0x7F || n == 0) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", u);
      s += buf;
    } else {
      s.append(shown.substr(i, n));
      i += n - 1;
    }
  }
  s += "\"";
  if (text.size() > kShown) s += "... (" + std::to_string(text.size()) + " bytes)";
  return s;
}

}  // namespace mc::host
