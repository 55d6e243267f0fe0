// The workpiece of the machine TOML ([workpiece]) as geometry: the true
// height of its top face anywhere, a height map sampled from it, and what a
// levelling comparison needs (an engraving program over the face and the
// depth error of a measured path against the face).
//
// Units: the config is SI (m); everything here is machine millimetres, as
// the interpreter, the planner and height maps are.
#pragma once

#include <string>
#include <vector>

#include "host/machine/height_map.hpp"
#include "host/machine/machine_config.hpp"
#include "host/motion/job_stream.hpp"
#include "host/motion/planner.hpp"

namespace mc::machine {

// The top face's machine Z (mm) at machine (x, y) (mm): plane + dish +
// roughness. The roughness is a smooth random field (values on a 5 mm
// lattice, bilinear between them) whose RMS is noise_m, the same for the
// same noise_seed.
double surface_z_mm(const WorkpieceConfig& w, double x_mm, double y_mm);

// surface_z_mm for a path of nearby points (the virtual probe asks every
// plant step): the same values, with the roughness's lattice values kept
// for the last 5 mm cell instead of hashed anew.
class SurfaceCache {
 public:
  explicit SurfaceCache(const WorkpieceConfig& w) : w_(w) {}
  double z_mm(double x_mm, double y_mm);
  // How far the face can rise or fall from (x, y) to any point within dx,
  // dy of it (mm; a bound from the slopes of plane, dish and roughness).
  double variation_mm(double x_mm, double y_mm, double dx_mm, double dy_mm) const;
  struct Cell {
    int64_t i = 0, j = 0;
    double v[4] = {};  // at (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)
    bool set = false;
  };

 private:
  WorkpieceConfig w_;
  Cell cell_;
};

// What a perfect probe would map: nx x ny points evenly over the workpiece,
// inset by `inset_mm` from its edges, heights relative to the first point.
HeightMap sample_height_map(const WorkpieceConfig& w, int nx, int ny, double inset_mm);

// An engraving `depth_mm` deep over the map's area: `rows` cuts along X and
// `columns` along Y, each from edge to edge of the map, at `feed_mm_min`,
// plunged at 300 mm/min with a 0.25 s dwell at depth before each cut, and
// rapids 3 mm above the work zero between them. Its work zero (G54) is
// machine Z `work_zero_z_mm` at the map's first point, where an operator
// would have zeroed Z on the face.
std::string engraving_program(const HeightMap& map, double work_zero_z_mm, double depth_mm,
                              double feed_mm_min, int rows, int columns);

// How far the measured tool tip was from `depth_mm` below the face, over
// the samples taken while the command moved in XY below the face's level
// at the start (the cuts, not the rapids or plunges): z measured minus
// (face - depth) at the measured X, Y; positive is too shallow.
struct DepthStats {
  double rms_mm = 0, max_mm = 0;    // max: the largest |error|
  double min_mm = 0, worst_mm = 0;  // the most negative (too deep) and most positive (too shallow)
  size_t n = 0;
};
DepthStats depth_error(const std::vector<mc::host::JobSample>& samples, const mc::host::PlannerConfig& cfg,
                       const WorkpieceConfig& w, const HeightMap& map, double depth_mm);

}  // namespace mc::machine
