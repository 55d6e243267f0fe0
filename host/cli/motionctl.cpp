// motionctl: the MotionCore host tool.
//
// Error contract, relied on by scripts and tests: any failure prints exactly
// one line "motionctl: error: ..." on stderr and exits non-zero (2 for bad
// usage or input, 1 for anything else); --help prints on stdout and exits 0.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "host/base/errors.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "host/machine/job.hpp"

namespace {

constexpr int kExitUsage = 2;
constexpr int kExitFailure = 1;

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// "motionctl coeffs" when the error is in a subcommand's arguments.
std::string command_path(const CLI::App& app) {
  std::string path = app.get_name();
  const CLI::App* a = &app;
  while (!a->get_subcommands().empty()) {
    a = a->get_subcommands().front();
    path += " " + a->get_name();
  }
  return path;
}

std::string command_names(CLI::App& app) {
  std::string names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return names;
}

int fail(const std::string& msg, int code) {
  std::cerr << "motionctl: error: " << one_line(msg) << '\n';
  return code;
}

int run(int argc, char** argv) {
  CLI::App app{
      "MotionCore host tool: drive and tune the board (--port DEV) or the virtual board (--sim), design "
      "controller coefficients, preview interpolated paths and run the axis plant model.",
      "motionctl"};
  // At most one command; "none" is reported by us, so that an unknown command
  // name is not misreported as a missing one.
  app.require_subcommand(0, 1);
  mc::host::cli::add_global_options(app);

  mc::host::cli::add_coeffs_command(app);
  mc::host::cli::add_interp_command(app);
  mc::host::cli::add_jitter_command(app);
  mc::host::cli::add_plant_command(app);
  mc::host::cli::add_cosim_command(app);
  mc::host::cli::add_bench_command(app);
  mc::host::cli::add_sim_command(app);
  mc::host::cli::add_status_command(app);
  mc::host::cli::add_board_commands(app);
  mc::host::cli::add_mpg_command(app);
  mc::host::cli::add_cycle_commands(app);
  mc::host::cli::add_gains_commands(app);
  mc::host::cli::add_step_commands(app);
  mc::host::cli::add_tune_command(app);
  mc::host::cli::add_hostloop_command(app);
  mc::host::cli::add_gcode_command(app);
  mc::host::cli::add_run_command(app);
  mc::host::cli::add_serve_command(app);
  mc::host::cli::add_level_command(app);

  // After the commands: subcommands inherit the footer they were created with.
  app.footer("Run 'motionctl COMMAND --help' for the options of a command.\n");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and version are "errors" with exit code 0 in CLI11.
    if (e.get_exit_code() == 0) return app.exit(e);
    if (dynamic_cast<const CLI::ExtrasError*>(&e) && app.get_subcommands().empty() && argc > 1 &&
        argv[1][0] != '-') {
      return fail("unknown command \"" + std::string(argv[1]) + "\"; expected one of: " + command_names(app) +
                      " (see 'motionctl --help')",
                  kExitUsage);
    }
    return fail(std::string(e.what()) + " (see '" + command_path(app) + " --help')", kExitUsage);
  }
  if (app.get_subcommands().empty()) {
    return fail("no command given; expected one of: " + command_names(app) + " (see 'motionctl --help')",
                kExitUsage);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Commands run inside parse() (CLI11 callbacks), so their errors arrive here.
  try {
    return run(argc, argv);
  } catch (const mc::machine::ProgramErrors& e) {
    // Every error of the program, one per line as compilers print them (an
    // editor jumps to each), then the one summary line.
    for (const auto& err : e.errors()) std::cerr << err.format() << '\n';
    const auto& first = e.errors().front();
    return fail(std::to_string(e.errors().size()) + " error(s) in " + first.file + "; nothing was run",
                kExitUsage);
  } catch (const mc::host::InputError& e) {
    return fail(e.what(), kExitUsage);
  } catch (const std::exception& e) {
    return fail(e.what(), kExitFailure);
  } catch (...) {
    return fail("unexpected internal error", kExitFailure);
  }
}
