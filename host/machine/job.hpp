// A G-code job on this machine: the program checked and planned with the
// machine's limits (configs/default.toml: max_speed_m_s, max_accel_m_s2,
// travel_*_m, [planner]), and the report of a run: time against plan, the
// command's acceleration, underruns and the contour error of the measured
// path against the programmed one.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "host/control/metrics.hpp"
#include "host/gcode/interpreter.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/height_map.hpp"
#include "host/machine/machine_config.hpp"
#include "host/motion/job_stream.hpp"
#include "host/motion/planner.hpp"

namespace mc::machine {

// The planner's limits from the machine (mm, mm/s, mm/s^2), in the machine
// frame whose zero is at board counts `origin` (mc::host::MachineOrigin:
// the board's, once homed).
mc::host::PlannerConfig planner_config(const MachineConfig& m, const mc::host::Vec3& origin = {});

// Every error of a program, FILE:LINE:COLUMN each (what() lists them all).
class ProgramErrors : public std::runtime_error {
 public:
  explicit ProgramErrors(std::vector<mc::gcode::Error> errors);
  const std::vector<mc::gcode::Error>& errors() const { return errors_; }

 private:
  std::vector<mc::gcode::Error> errors_;
};

struct Job {
  std::string file;
  mc::host::PlannerConfig cfg;
  int lines = 0;  // lines read
  std::vector<mc::host::Move> moves;
  std::vector<mc::host::Piece> pieces;
  mc::host::PlanSummary summary;
};

// Interprets the whole file from `start` (machine mm) and plans it; with
// `level`, the program follows that height map (height_map.hpp), arcs and
// splits within the machine's arc tolerance. Throws ProgramErrors for
// G-code errors and InputError ("FILE:line N: ...") for what the machine
// cannot do (travel, an absent axis, a probe, a cut outside the map); in
// every case before anything moves.
// How a map is applied: split per cell and within the tolerance, or only at
// each move's end points (the source paper's method, kept for comparison).
enum class LevelMethod { bilinear, end_points };
// origin: as planner_config's; the job's segments go to the board in its
// counts.
Job plan_job(const std::string& path, const MachineConfig& m, const mc::host::Vec3d& start,
             const HeightMap* level = nullptr, const mc::host::Vec3& origin = {});
Job plan_program(std::string_view text, const std::string& name, const MachineConfig& m,
                 const mc::host::Vec3d& start, const HeightMap* level = nullptr,
                 LevelMethod method = LevelMethod::bilinear, const mc::host::Vec3& origin = {});

// A board ready to run a job: every axis of the machine present, gains
// where the board has none (the machine's, with a note), the drives armed,
// the PIDs enabled and the following-error limits armed. Throws InputError
// when the board has fewer axes than the machine, BoardError for a latched
// fault other than the watchdog's.
struct JobBoard {
  std::vector<int> axes;
  mc::host::Vec3 at{};      // the interpolator's position, counts: where the job starts
  double ts_s = 0;          // the PID sample period
  mc::host::Vec3 origin{};  // the board's machine zero (MachineOrigin), counts
};
JobBoard ready_board(mc::host::BoardLink& l, const MachineConfig& m, const mc::host::Note& note);

struct JobReport {
  double planned_s = 0;  // of what ran
  double board_s = 0;    // the board's time from the first to the last sample (telemetry), 0 without
  int underruns = 0;
  size_t segments = 0;
  double segments_per_s = 0;            // segments / board time
  std::array<double, 3> peak_accel{};   // mm/s^2, the command (planner.hpp peak_accel)
  std::array<double, 3> accel_limit{};  // mm/s^2
  mc::host::ErrorStats contour;         // mm: measured position against the programmed path
  mc::host::ErrorStats following;       // mm: |command - position|, the worst axis per sample
  int64_t telemetry_gaps = 0;
  bool stopped = false;
  int stopped_at_line = 0;
};

// Contour error of the samples (counts) against the path of the moves:
// each sample's distance from the nearest move around the one its command
// lies on; samples whose command is on a rapid are left out.
mc::host::ErrorStats contour_error(const std::vector<mc::host::JobSample>& samples,
                                   const std::vector<mc::host::Move>& moves,
                                   const mc::host::PlannerConfig& cfg);
// The same with each sample's position in mm (cmd[i] in counts goes with
// pos_mm[i]): a simulation's true table position, which no encoder rounds.
// each (optional): every sample's distance, mm, NaN where the command is on
// a rapid.
mc::host::ErrorStats contour_error(const std::vector<std::array<int32_t, 3>>& cmd,
                                   const std::vector<mc::host::Vec3d>& pos_mm,
                                   const std::vector<mc::host::Move>& moves,
                                   const mc::host::PlannerConfig& cfg, std::vector<double>* each = nullptr);

JobReport report(const Job& job, const mc::host::StreamResult& r, double ts_s);

}  // namespace mc::machine
