#include "sim/vboard/board_stream.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>

#include "host/base/errors.hpp"
#include "host/control/board_gains.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/workpiece.hpp"
#include "host/motion/board_run.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::sim {

namespace {
constexpr double kClearZ_m = 0.005;  // measure_vboard_speed's Z above the face
}  // namespace

size_t BoardStream::read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) {
  const uint64_t end = b_.cycles() + uint64_t(double(timeout.count()) * 1e-3 * b_.clock_hz());
  while (pending_.empty() && b_.cycles() < end) {
    const size_t before = pending_.size();
    b_.run(end - b_.cycles(), pending_, true);
    if (!log_) continue;
    for (size_t i = before; i < pending_.size(); ++i) tx.emplace_back(b_.cycles(), pending_[i]);
    for (int a = 0; a < kBoardAxes; ++a) pos.push_back(b_.position_m(a));
  }
  const size_t k = std::min(n, pending_.size());
  std::copy(pending_.begin(), pending_.begin() + long(k), p);
  pending_.erase(pending_.begin(), pending_.begin() + long(k));
  return k;
}

VBoardSpeed measure_vboard_speed(const MachineConfig& m, BoardEngine e, const std::string& workload,
                                 double board_s) {
  namespace br = board::reg;
  if (workload != "hold" && workload != "move")
    throw mc::host::InputError("workload", "'" + workload + "'", "hold or move");
  VirtualBoard board(m, 0, e);
  // Z clear of the workpiece, as between cuts: a probe dragged along the
  // face would chatter on its roughness, which no job does.
  if (m.workpiece && board.configured_axes() > 2)
    board.start_at(2, mc::machine::surface_z_mm(*m.workpiece, 0, 0) * 1e-3 + kClearZ_m);
  BoardStream s(board);
  mc::host::BoardLink link(s);
  const mc::host::Note quiet = [](const std::string&) {};
  link.connect();
  link.write(br::WDOG, (1u << 24) - 1);
  std::vector<int> axes;
  for (int a = 0; a < board.configured_axes(); ++a) {
    const mc::machine::PidConfig& c = m.axes[size_t(a)].pid;
    mc::host::PidGains g{};
    g.kp = c.kp;
    g.ki = c.ki;
    g.kd = c.kd;
    g.tf = c.tf_s;
    g.ts = 100e-6;
    mc::host::CoreLimits lim;
    lim.out_limit = uint32_t(std::lround(c.out_limit));
    mc::host::apply_gains(link, a, g, lim, quiet);
    axes.push_back(a);
  }
  mc::host::enable_axes(link, axes, quiet);

  VBoardSpeed r;
  r.workload = workload;
  r.engine = e;
  r.axes = board.configured_axes();
  const uint64_t c0 = board.cycles(), s0 = board.stepped_clocks();
  const uint64_t end = c0 + uint64_t(board_s * board.clock_hz());
  const auto t0 = std::chrono::steady_clock::now();
  const auto cpu = [] {
    timespec ts{};
    ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  };
  const double cpu0 = cpu();
  const double cpm = mc::machine::counts_per_m(m.axes[0]);
  const int64_t stroke = std::llround(0.5e-3 * cpm);  // 0.5 mm each way
  bool out = true;
  while (board.cycles() < end) {
    if (workload == "move" && !(link.read(br::IP_STAT) >> board::bits::IS_BUSY & 1)) {
      const mc::host::Vec3 from{out ? 0 : stroke, out ? 0 : -stroke, 0},
          to{out ? stroke : 0, out ? -stroke : 0, 0};
      const auto segs = mc::host::plan_move(from, to, 0.025 * cpm, m.clock_hz);
      std::vector<seg::Words> words;
      words.reserve(segs.size());
      for (const auto& p : segs) words.push_back(seg::pack(p.seg));
      for (size_t i = 0; i < words.size(); i += 6) {
        const std::vector<seg::Words> batch(words.begin() + long(i),
                                            words.begin() + long(std::min(words.size(), i + 6)));
        while (!link.segments(batch)) link.poll(std::chrono::milliseconds(1));
      }
      out = !out;
    }
    link.poll(std::chrono::milliseconds(10));
    link.read(br::STATUS);
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.cpu_s = cpu() - cpu0;
  r.clocks = board.cycles() - c0;
  r.stepped = board.stepped_clocks() - s0;
  r.board_s = double(r.clocks) / board.clock_hz();
  return r;
}

}  // namespace mc::sim
