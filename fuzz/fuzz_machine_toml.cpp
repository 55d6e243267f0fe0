// libFuzzer target: the machine TOML loader (host/machine/machine_config) on
// arbitrary text. A file is either accepted, and then every number the tools
// derive from it is finite and positive where it must be, or refused with an
// InputError that names the file and line; never anything else.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "host/base/errors.hpp"
#include "host/machine/machine_config.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

bool positive(double v) {
  return std::isfinite(v) && v > 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const mc::machine::MachineConfig m = mc::machine::parse_machine(text, "fuzz.toml");
    check(positive(m.clock_hz) && positive(m.plant_dt_s) && positive(m.host_period_s));
    check(!m.axes.empty());
    for (const mc::machine::AxisConfig& a : m.axes) {
      check(positive(mc::machine::counts_per_m(a)));
      check(std::isfinite(mc::machine::reflected_inertia_kg_m2(a)));
      // Names are unique: a lookup by name finds this very axis.
      check(&mc::machine::axis(m, a.name) == &a);
    }
  } catch (const mc::host::InputError& e) {
    // Errors carry their place: "fuzz.toml:LINE: ...".
    check(std::string_view(e.what()).rfind("fuzz.toml:", 0) == 0);
  }
  return 0;
}
