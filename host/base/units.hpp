// Parsing of the numbers users type on the command line and in config files.
// Strict on purpose: a sample period of "1O0us" or "100 usec" must be an error
// with the input quoted, never a silently different controller.
#pragma once

#include <string>
#include <string_view>

namespace mc::host {

enum class Zero { reject, allow };

// A duration in seconds: plain seconds ("0.0001", "1e-4") or a number with a
// unit s, ms, us (also µs), ns ("10ms", "100us", "2.5 us"). Negative values,
// non-numbers, inf/nan, unknown units and trailing characters throw InputError
// naming `what`; zero is rejected unless `zero` is Zero::allow.
double parse_duration(std::string_view text, std::string_view what = "duration", Zero zero = Zero::reject);

// A finite decimal number ("2", "-0.5", "1e-3"); no units, no inf/nan, no hex.
double parse_number(std::string_view text, std::string_view what = "number");

// Seconds as a short human string with the most readable unit: "100 us", "10 ms".
std::string format_duration(double seconds);

}  // namespace mc::host
