// The levelling comparison of docs/levelling.md: the same engraving run on
// a board three times over the machine's workpiece, without levelling, with
// the source paper's end-point method and with the bilinear map split per
// cell, and the depth of each cut measured against the workpiece's face.
// The face is the machine TOML's [workpiece], so the numbers mean something
// only on the virtual board, whose plant is that machine.
#pragma once

#include <string>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/machine_config.hpp"
#include "host/machine/workpiece.hpp"

namespace mc::machine {

struct LevelCompareOptions {
  int nx = 9, ny = 7;         // map points
  double inset_mm = 5;        // the map's edge inside the workpiece's
  double depth_mm = 0.1;      // engraving depth
  double feed_mm_min = 1500;  // cutting feed
  int rows = 3, columns = 2;  // cuts along X and along Y
  // Probe the map on the board (probe_grid, from 3 mm above the face)
  // instead of sampling the face as a perfect probe would.
  bool probe = false;
};

struct LevelCompareRun {
  std::string method;  // "none", "end points (paper)", "bilinear, split per cell"
  DepthStats depth;
  double planned_s = 0;
  int underruns = 0;
};

struct LevelComparison {
  HeightMap map;  // what a perfect probe takes of the face, or what the board's probe took
  double work_zero_z_mm =
      0;                // machine Z the engraving's G54 Z0 is at: the face (or contact) at the first point
  std::string program;  // the engraving
  std::vector<LevelCompareRun> runs;
};

// Throws InputError when the machine has no [workpiece] or no Z axis;
// `note` is told which run starts.
LevelComparison compare_levelling(mc::host::BoardLink& l, const MachineConfig& m,
                                  const LevelCompareOptions& o, const mc::host::Note& note);

}  // namespace mc::machine
