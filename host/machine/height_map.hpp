// Bed levelling: a height map probed on a regular XY grid, and a program's
// canonical calls deformed by it so that the tool follows the bed.
//
// The map holds the height of the surface at each grid point relative to
// the first one (the point the operator zeroed Z on): levelling adds the
// bilinear interpolation of the map at (x, y) to every Z of the path. A
// straight move is split where it crosses a grid line, so that no piece
// spans more than one cell, and again where the bilinear surface's twist
// would take the straight piece further than the tolerance from it; an arc
// becomes chords within the tolerance first. A cutting move (feed or arc)
// that leaves the mapped area is refused with its line: the map says
// nothing there. Rapids outside it take the height of the nearest edge.
//
// File format (TOML), written by `motionctl level probe` or by hand:
//
//   [map]
//   x0_mm = 10.0          # machine X of the first column
//   y0_mm = 10.0          # machine Y of the first row
//   dx_mm = 20.0          # column spacing, > 0
//   dy_mm = 20.0          # row spacing, > 0
//   heights_mm = [        # one row per Y from y0 up, one value per X from x0 up
//     [0.0, 0.012, 0.031],
//     [0.004, 0.020, 0.037],
//   ]
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "host/gcode/canon.hpp"

namespace mc::machine {

struct HeightMap {
  double x0 = 0, y0 = 0, dx = 1, dy = 1;
  int nx = 0, ny = 0;     // columns (X) and rows (Y), each >= 2
  std::vector<double> z;  // nx * ny, row by row: z[j * nx + i] at (x0 + i dx, y0 + j dy)

  double x1() const { return x0 + dx * (nx - 1); }
  double y1() const { return y0 + dy * (ny - 1); }
  double at(int i, int j) const { return z[size_t(j) * size_t(nx) + size_t(i)]; }
  // The cell holding (x, y), or the nearest one outside the area: its
  // corner (i, j) and where in it the point lies (0..1 each way).
  struct Cell {
    int i, j;
    double fu, fv;
  };
  Cell cell(double x, double y) const;
  // Bilinear inside the area; outside, the value at the nearest point of it.
  double height(double x, double y) const;
  // d2z/dxdy of the bilinear surface in a cell (mm^-1): 0 when its four
  // corners lie on one plane.
  double twist(int i, int j) const;
  // Inside the area, with a margin of `eps` mm.
  bool contains(double x, double y, double eps = 1e-9) const;
};

// Throws InputError naming `source` and the line for bad TOML, a missing or
// unknown key, rows of unequal length, fewer than 2 x 2 points, a spacing
// that is not > 0, a height that is not finite.
HeightMap parse_height_map(std::string_view toml_text, const std::string& source);
HeightMap load_height_map(const std::string& path);
// The file format above, every height with 6 decimals (nm).
std::string format_height_map(const HeightMap& map);

struct LevelOptions {
  double tolerance_mm = 0.002;  // chord error of arcs and of pieces on the twisted surface
};

// The calls of a program with the map applied, starting at `start` (machine
// mm, the machine's position before the first call). Probes are refused
// (a levelled job runs from known positions only), as are cutting moves that
// leave the map's area: InputError "FILE:LINE" (`file` may be empty).
std::vector<gcode::CanonCall> level_calls(const std::vector<gcode::CanonCall>& calls,
                                          const gcode::Vec3& start, const HeightMap& map,
                                          const LevelOptions& options = {}, const std::string& file = "");

// The source paper's method (seed 002, "interpolación lineal"): each move's
// end points get the map's height there and the move stays one straight
// line between them; arcs become chords within the tolerance, as its CAM
// output did. For the comparison in docs/levelling.md.
std::vector<gcode::CanonCall> level_calls_endpoints(const std::vector<gcode::CanonCall>& calls,
                                                    const gcode::Vec3& start, const HeightMap& map,
                                                    const LevelOptions& options = {},
                                                    const std::string& file = "");

}  // namespace mc::machine
