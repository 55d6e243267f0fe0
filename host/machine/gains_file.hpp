// The gains file of `motionctl config save|load`: every axis' gains and
// limits and the shared sample period as TOML, read from and written to a
// board. A file is parsed and checked whole before anything is written.
#pragma once

#include <string>
#include <vector>

#include "host/control/board_gains.hpp"
#include "host/link/board_link.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {

struct GainsEntry {
  int axis = 0;
  mc::host::PidGains gains{};
  mc::host::CoreLimits limits;
  uint32_t ferr = 0;  // following-error limit, counts
};
struct GainsFile {
  double ts_s = 0;
  std::vector<GainsEntry> axes;
};

// Parses and checks a file as 'config save' writes it; InputError naming the
// file, the table and the key.
GainsFile read_gains_file(const std::string& path);
// The board's gains as a file; returns how many axes it wrote.
int save_gains(mc::host::BoardLink& l, const std::string& path);
// Writes a parsed file to the board (each axis verified word by word);
// returns how many axes it loaded.
int load_gains(mc::host::BoardLink& l, const GainsFile& f, const std::string& path,
               const mc::host::Note& warn);

// Gives every servo axis of the machine that has no gains on the board (Kp = Ki =
// 0, as after power-up) the machine config's, with a note for each; axes
// with gains keep them. Returns how many axes it wrote.
int gains_where_missing(mc::host::BoardLink& l, const MachineConfig& m, const mc::host::Note& note);

}  // namespace mc::machine
