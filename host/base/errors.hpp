// The one exception type for bad user input in the host library. Every message
// names the quantity, quotes the offending value and says what was expected, so
// that a CLI can print it as a single line and the user can fix the input
// without reading the source.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace mc::host {

class InputError : public std::invalid_argument {
 public:
  // quantity: what was wrong ("ts", "--kp", "kd_b = 2Kd/(2Tf+Ts)");
  // value: the value as the user wrote it (quoted text) or as computed;
  // expected: what would have been accepted; problem: optional short diagnosis.
  InputError(std::string quantity, std::string value, std::string expected, std::string problem = {})
      : std::invalid_argument(compose(quantity, value, expected, problem)),
        quantity_(std::move(quantity)),
        value_(std::move(value)),
        expected_(std::move(expected)),
        problem_(std::move(problem)) {}

  const std::string& quantity() const { return quantity_; }
  const std::string& value() const { return value_; }
  const std::string& expected() const { return expected_; }
  const std::string& problem() const { return problem_; }

 private:
  static std::string compose(const std::string& q, const std::string& v, const std::string& e,
                             const std::string& p) {
    std::string s = q + " = " + v + ": ";
    if (!p.empty()) s += p + "; ";
    return s + "expected " + e;
  }

  std::string quantity_, value_, expected_, problem_;
};

// Numbers in messages: enough digits to show what went wrong, no more.
std::string format_number(double v);

// Text in messages: double-quoted, control characters and bytes that are not
// UTF-8 escaped (\xNN), cut after 200 bytes with the length said, so that the
// message stays on one line.
std::string quote(std::string_view text);

}  // namespace mc::host
