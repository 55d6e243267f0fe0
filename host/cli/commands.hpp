// motionctl subcommands. Each one registers itself on the top-level CLI::App
// with its options and a callback that runs it; main() only adds them and
// turns errors into one line. A new command is one more add_*_command here,
// one cmd_*.cpp, and one line in motionctl.cpp.
#pragma once

namespace CLI {
class App;
}

namespace mc::host::cli {

void add_coeffs_command(CLI::App& app);
void add_interp_command(CLI::App& app);
void add_jitter_command(CLI::App& app);
void add_plant_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_cosim_command(CLI::App& app);
void add_sim_command(CLI::App& app);
// motionctl sim soak (cmd_soak.cpp), under the sim command.
void add_soak_command(CLI::App& sim);
void add_status_command(CLI::App& app);
void add_board_commands(CLI::App& app);
void add_mpg_command(CLI::App& app);
void add_gains_commands(CLI::App& app);
void add_step_commands(CLI::App& app);
void add_tune_command(CLI::App& app);
void add_hostloop_command(CLI::App& app);
void add_gcode_command(CLI::App& app);
void add_run_command(CLI::App& app);
void add_serve_command(CLI::App& app);
void add_level_command(CLI::App& app);
void add_cycle_commands(CLI::App& app);

}  // namespace mc::host::cli
