#include "host/base/units.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>
#include <system_error>

#include "host/base/errors.hpp"

namespace mc::host {
namespace {

constexpr const char* kNumberExpected = "a finite decimal number such as 2, 0.05 or 1e-3";
constexpr const char* kDurationExpected =
    "seconds (e.g. 1e-4) or a number with a unit s, ms, us, ns (e.g. 100us, 10ms)";

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

std::string_view trim(std::string_view s) {
  const auto sp = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && sp(s.front())) s.remove_prefix(1);
  while (!s.empty() && sp(s.back())) s.remove_suffix(1);
  return s;
}

// A decimal number split into its parts, so that a unit can be applied by
// shifting the exponent: "0.1ms" is then converted as 0.1e-3 in one correctly
// rounded step, and equals the double that "1e-4" gives.
struct Scanned {
  bool negative = false;
  std::string digits;  // mantissa with its decimal point, no sign
  long exponent = 0;
  std::string_view rest;
};

std::optional<Scanned> scan_number(std::string_view s) {
  Scanned r;
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) r.negative = s[i++] == '-';
  std::size_t ndig = 0;
  while (i < s.size() && is_digit(s[i])) {
    r.digits += s[i++];
    ++ndig;
  }
  if (i < s.size() && s[i] == '.') {
    r.digits += s[i++];
    while (i < s.size() && is_digit(s[i])) {
      r.digits += s[i++];
      ++ndig;
    }
  }
  if (ndig == 0) return std::nullopt;
  // An exponent only when digits follow: "1e" or "1es" is junk, not 1.
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    std::size_t j = i + 1;
    bool eneg = false;
    if (j < s.size() && (s[j] == '+' || s[j] == '-')) eneg = s[j++] == '-';
    if (j < s.size() && is_digit(s[j])) {
      long e = 0;
      while (j < s.size() && is_digit(s[j])) {
        // Clamp: beyond this the value is 0 or inf anyway, and both are rejected.
        if (e < 100000) e = e * 10 + (s[j] - '0');
        ++j;
      }
      r.exponent = eneg ? -e : e;
      i = j;
    }
  }
  r.rest = s.substr(i);
  return r;
}

// Converts a scanned magnitude times 10^shift. nullopt when out of range.
std::optional<double> to_double(const Scanned& n, long shift) {
  const std::string t = n.digits + "e" + std::to_string(n.exponent + shift);
  double v = 0;
  const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || p != t.data() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<long> unit_exponent(std::string_view u) {
  if (u.empty() || u == "s") return 0;
  if (u == "ms") return -3;
  // "\u00b5" is MICRO SIGN, "\u03bc" GREEK SMALL LETTER MU: keyboards produce either.
  if (u == "us" || u == "\xC2\xB5s" || u == "\xCE\xBCs") return -6;
  if (u == "ns") return -9;
  return std::nullopt;
}

}  // namespace

double parse_duration(std::string_view text, std::string_view what, Zero zero) {
  const std::string q{what}, v = quote(text);
  const std::string expected =
      std::string(zero == Zero::allow ? "a duration >= 0: " : "a duration > 0: ") + kDurationExpected;
  const std::string_view s = trim(text);
  const auto n = scan_number(s);
  if (!n) throw InputError(q, v, expected, "not a number");
  const auto ue = unit_exponent(trim(n->rest));
  if (!ue) {
    throw InputError(q, v, expected, "unknown unit or trailing characters " + quote(trim(n->rest)));
  }
  const auto d = to_double(*n, *ue);
  if (!d) throw InputError(q, v, expected, "out of range");
  if (n->negative && *d != 0) throw InputError(q, v, expected, "negative");
  if (*d == 0 && zero == Zero::reject) throw InputError(q, v, expected, "zero");
  return *d;
}

double parse_number(std::string_view text, std::string_view what) {
  const std::string q{what}, v = quote(text);
  const auto n = scan_number(trim(text));
  if (!n) throw InputError(q, v, kNumberExpected, "not a number");
  if (!n->rest.empty()) throw InputError(q, v, kNumberExpected, "trailing characters " + quote(n->rest));
  const auto d = to_double(*n, 0);
  if (!d) throw InputError(q, v, kNumberExpected, "out of range");
  return n->negative ? -*d : *d;
}

std::string format_duration(double seconds) {
  struct U {
    double scale;
    const char* name;
  };
  static constexpr U units[] = {{1.0, "s"}, {1e-3, "ms"}, {1e-6, "us"}, {1e-9, "ns"}};
  const double a = std::fabs(seconds);
  if (a == 0 || !std::isfinite(a)) return format_number(seconds) + " s";
  for (const U& u : units) {
    if (a >= u.scale || u.scale == units[3].scale) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "%.6g %s", seconds / u.scale, u.name);
      return buf;
    }
  }
  return {};
}

}  // namespace mc::host
