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
};

struct LevelCompareRun {
  std::string method;  // "none", "end points (paper)", "bilinear, split per cell"
  DepthStats depth;
  double planned_s = 0;
  int underruns = 0;
};

struct LevelComparison {
  HeightMap map;        // what a perfect probe takes of the face
  std::string program;  // the engraving
  std::vector<LevelCompareRun> runs;
};

// Throws InputError when the machine has no [workpiece] or no Z axis;
// `note` is told which run starts.
LevelComparison compare_levelling(mc::host::BoardLink& l, const MachineConfig& m,
                                  const LevelCompareOptions& o, const mc::host::Note& note);

}  // namespace mc::machine
