// motionctl coeffs: design the Tustin PID for given gains and show the
// coefficient words the core would be loaded with, and what they realize.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "host/base/units.hpp"
#include "host/cli/commands.hpp"
#include "host/control/pid_design.hpp"

namespace mc::host::cli {
namespace {

struct CoeffsOptions {
  std::string kp, ki = "0", kd = "0", tf = "0", ts, ff1 = "0", ff2 = "0";
  bool json = false;
};

// Keys in the order a reader expects (gains, design, words), not sorted.
nlohmann::ordered_json to_json(const PidDesign& d) {
  using json = nlohmann::ordered_json;
  const PidGains& g = d.gains;
  json j;
  j["ts"] = g.ts;
  j["kp"] = g.kp;
  j["ki"] = g.ki;
  j["kd"] = g.kd;
  j["tf"] = g.tf;
  j["ff1"] = g.ff1;
  j["ff2"] = g.ff2;
  j["b"] = d.tf.b;
  j["a"] = d.tf.a;
  if (d.seed) j["seed_form"] = {{"ka", d.seed->ka}, {"kb", d.seed->kb}, {"kc", d.seed->kc}};
  json fixed = json::object();
  for (const FixedCoef& f : d.fixed) {
    fixed[std::string(f.name)] = {
        {"word", f.word},   {"mantissa", f.coef.m}, {"shift", f.coef.s},
        {"value", f.value}, {"design", f.design},   {"rel_error", f.rel_error},
    };
  }
  j["fixed"] = fixed;
  j["fixed_b"] = d.fixed_tf.b;
  j["fixed_a"] = d.fixed_tf.a;
  j["max_rel_error"] = d.max_rel_error;
  return j;
}

std::string g10(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string list(const std::array<double, 3>& v) {
  return "[" + g10(v[0]) + ", " + g10(v[1]) + ", " + g10(v[2]) + "]";
}

void print_human(const PidDesign& d, std::ostream& os) {
  const PidGains& g = d.gains;
  char line[256];
  os << "Tustin PID  C(s) = Kp + Ki/s + Kd*s/(Tf*s + 1),  s = (2/Ts)(z-1)/(z+1)\n";
  os << "  Ts = " << g10(g.ts) << " s (" << format_duration(g.ts) << ")   Tf = " << g10(g.tf) << " s\n";
  os << "  Kp = " << g10(g.kp) << "   Ki = " << g10(g.ki) << "   Kd = " << g10(g.kd);
  if (g.ff1 != 0 || g.ff2 != 0) os << "   FF1 = " << g10(g.ff1) << "   FF2 = " << g10(g.ff2);
  os << "\n  (drive units, full scale +-32767, per encoder count; Ki per count*s, Kd per count/s)\n\n";

  os << "Discrete controller  C(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)\n";
  os << "  b = " << list(d.tf.b) << "\n  a = " << list(d.tf.a) << "\n";
  if (d.seed) {
    os << "  seed form: u(k) = KA e(k) + KB e(k-1) + KC e(k-2) + u(k-2)\n";
    os << "    KA = " << g10(d.seed->ka) << "   KB = " << g10(d.seed->kb) << "   KC = " << g10(d.seed->kc)
       << "\n";
  }
  os << "\nCore coefficients (parallel form; value = mantissa * 2^(fx - shift))\n";
  std::snprintf(line, sizeof line, "  %-5s %-18s %-17s %-10s %9s %5s %3s %-17s %s\n", "reg", "formula",
                "design", "word", "mantissa", "shift", "fx", "realized", "rel.error");
  os << line;
  for (const FixedCoef& f : d.fixed) {
    char word[16];
    std::snprintf(word, sizeof word, "0x%08X", unsigned(f.word));
    std::snprintf(line, sizeof line, "  %-5s %-18s %-17.10g %-10s %9d %5d %3d %-17.10g %.3g%s\n",
                  std::string(f.name).c_str(), std::string(f.formula).c_str(), f.design, word, int(f.coef.m),
                  f.coef.s, f.fx, f.value, f.rel_error, f.lost ? "  LOST (below resolution)" : "");
    os << line;
  }
  os << "\nRealized by the quantized coefficients\n";
  os << "  b = " << list(d.fixed_tf.b) << "\n  a = " << list(d.fixed_tf.a) << "\n";
  std::snprintf(line, sizeof line, "  max rel. error of a coefficient: %.3g\n", d.max_rel_error);
  os << line;
  if (g.tf == 0) {
    os << "\nnote: Tf = 0: the pure Tustin derivative has its pole at z = -1 (Nyquist), so the D term\n"
          "      alternates sign every sample on encoder noise. Elsewhere MotionCore defaults to Tf > 0\n"
          "      (e.g. --tf of a few Ts).\n";
  }
}

void run(const CoeffsOptions& o) {
  PidGains g{};
  g.kp = parse_number(o.kp, "--kp");
  g.ki = parse_number(o.ki, "--ki");
  g.kd = parse_number(o.kd, "--kd");
  g.ff1 = parse_number(o.ff1, "--ff1");
  g.ff2 = parse_number(o.ff2, "--ff2");
  g.tf = parse_duration(o.tf, "--tf", Zero::allow);
  g.ts = parse_duration(o.ts, "--ts");
  const PidDesign d = design(g);
  for (const FixedCoef& f : d.fixed) {
    if (f.lost) {
      std::cerr << "motionctl: warning: " << f.name << " = " << f.formula << " = " << g10(f.design)
                << " is below the resolution of the coefficient word and is realized as 0\n";
    }
  }
  if (o.json) {
    std::cout << to_json(d).dump(2) << '\n';
  } else {
    print_human(d, std::cout);
  }
}

}  // namespace

void add_coeffs_command(CLI::App& app) {
  auto opt = std::make_shared<CoeffsOptions>();
  CLI::App* sub = app.add_subcommand(
      "coeffs", "Design a Tustin PID for the core: discrete controller and coefficient words");
  sub->footer(
      "Designs C(s) = Kp + Ki/s + Kd*s/(Tf*s + 1) with s = (2/Ts)(z-1)/(z+1) and quantizes the\n"
      "parallel-form coefficients into the core's words (mantissa * 2^(fx - shift)).\n"
      "Gains are in drive units (full scale +-32767) per encoder count.");
  sub->add_option("--kp", opt->kp, "Proportional gain, drive units per count")->required()->type_name("GAIN");
  sub->add_option("--ki", opt->ki, "Integral gain, drive units per count*s (default 0)")->type_name("GAIN");
  sub->add_option("--kd", opt->kd, "Derivative gain, drive units per count/s (default 0)")->type_name("GAIN");
  sub->add_option("--tf", opt->tf, "Derivative filter time constant (default 0: no filter), e.g. 500us")
      ->type_name("TIME");
  sub->add_option("--ts", opt->ts, "Sample period, e.g. 100us, 1ms, 1e-4")->required()->type_name("TIME");
  sub->add_option("--ff1", opt->ff1, "Velocity feedforward, drive units per count/s (default 0)")
      ->type_name("GAIN");
  sub->add_option("--ff2", opt->ff2, "Acceleration feedforward, drive units per count/s^2 (default 0)")
      ->type_name("GAIN");
  sub->add_flag("--json", opt->json, "Print one JSON object instead of the table");
  sub->callback([opt] { run(*opt); });
}

}  // namespace mc::host::cli
