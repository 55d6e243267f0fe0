// Auto-levelling's measurement: the probe touched down on every point of an
// XY grid (ProbeCycle, on the board's latch), the heights written as a
// height map (height_map.hpp) relative to the first point, the one an
// operator zeroes Z on.
#pragma once

#include <functional>

#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/height_map.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {

struct ProbeGridOptions {
  int nx = 3, ny = 3;                     // points along X and Y, each >= 2
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // the area's corners, machine mm (x0 < x1, y0 < y1)
  double feed_mm_min = 300;               // probing feed: the latch is exact at any feed, the stop is not
  double travel_mm_min = 1500;            // the moves between points
  double clearance_mm = 2;                // between points, the tool rises this far above the highest contact
  double depth_mm = 20;                   // how far below where it started the probe searches
};

struct ProbedGrid {
  HeightMap map;     // heights relative to the first point (x0, y0)
  double z0_mm = 0;  // machine Z of the contact at the first point
};

// InputError for a grid or an area probe_grid() would refuse (before any
// board is touched; the travel is checked once the board is).
void check_probe_grid(const ProbeGridOptions& o);

// Probes the grid row by row (back and forth along X), starting where the
// tool stands, which must be above the work: the first move goes to (x0, y0)
// at that height. Between points the tool rises to clearance_mm above the
// highest contact so far and moves there. Readies the board as a job does.
// InputError for a bad grid or area, or one outside the travel; CycleError
// 4 when the probe touches before a point's descent, 5 when a point finds
// nothing within depth_mm. `progress(done, total)` once the checks passed
// and the board is ready (done 0), then after each point.
ProbedGrid probe_grid(mc::host::BoardLink& l, const MachineConfig& m, const ProbeGridOptions& o,
                      const mc::host::Note& note = {}, const std::function<void(int, int)>& progress = {});

}  // namespace mc::machine
