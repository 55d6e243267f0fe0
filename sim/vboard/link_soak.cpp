#include "sim/vboard/link_soak.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <map>
#include <optional>

#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/gains_file.hpp"
#include "host/machine/job.hpp"
#include "host/motion/job_stream.hpp"
#include "sim/vboard/board_stream.hpp"

namespace mc::sim {

namespace br = board::reg;

SegmentTally& SegmentTally::operator+=(const SegmentTally& o) {
  sent += o.sent;
  applied += o.applied;
  matched += o.matched;
  lost += o.lost;
  doubled += o.doubled;
  reordered += o.reordered;
  foreign += o.foreign;
  partial += o.partial;
  return *this;
}

SegmentTally tally_segments(const std::vector<seg::Words>& sent, const std::vector<uint32_t>& words,
                            size_t window) {
  SegmentTally t;
  t.sent = sent.size();
  t.applied = words.size() / seg::SEG_WORDS;
  t.partial = words.size() % seg::SEG_WORDS;
  std::map<seg::Words, uint64_t> skipped;  // sent, passed over, not seen yet
  size_t i = 0;
  for (size_t j = 0; j < t.applied; ++j) {
    seg::Words a{};
    std::copy_n(words.begin() + long(j * seg::SEG_WORDS), seg::SEG_WORDS, a.begin());
    if (i < sent.size() && a == sent[i]) {
      ++t.matched;
      ++i;
      continue;
    }
    if (auto s = skipped.find(a); s != skipped.end()) {
      ++t.reordered;
      if (--s->second == 0) skipped.erase(s);
      continue;
    }
    bool again = false;
    for (size_t k = i; k > 0 && i - k < window && !again; --k) again = sent[k - 1] == a;
    if (again) {
      ++t.doubled;
      continue;
    }
    size_t d = 1;
    while (d <= window && i + d < sent.size() && !(sent[i + d] == a)) ++d;
    if (d <= window && i + d < sent.size()) {
      for (size_t k = i; k < i + d; ++k) ++skipped[sent[k]];
      i += d + 1;
      ++t.matched;
      continue;
    }
    ++t.foreign;
  }
  t.lost = sent.size() - i;
  for (const auto& [w, n] : skipped) t.lost += n;
  return t;
}

namespace {

double thread_cpu_s() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// A job planned from one start (counts); a loop of the job starts its
// second and later passes where the first ended, so two plans serve them all.
struct Plan {
  host::Vec3 start{};
  machine::Job job;
  std::vector<seg::Words> sent;  // the segments of the job, in order
};

}  // namespace

SoakResult run_link_soak(const MachineConfig& m, const SoakOptions& o) {
  if (!(o.board_s > 0))
    throw host::InputError("board time", host::format_number(o.board_s) + " s", "above 0");
  for (const auto& [what, rate] : {std::pair{"flip rate", o.flip_rate}, std::pair{"drop rate", o.drop_rate}})
    if (!(rate >= 0 && rate < 0.1))
      throw host::InputError(what, host::format_number(rate), "from 0 to below 0.1 per byte");
  const host::PlannerConfig cfg = machine::planner_config(m);
  // The whole program checked before the board is touched: from the origin.
  machine::plan_job(o.job, m, {0, 0, 0});

  VirtualBoard board(m, 0, o.engine);
  BoardStream stream(board);
  host::FaultInjector line(stream, o.flip_rate, o.drop_rate, o.seed);
  host::BoardLink link(line, o.link);
  std::vector<uint32_t> tap;
  board.tap_segments(&tap);
  const host::Note quiet = [](const std::string&) {};

  SoakResult r;
  r.job = o.job;
  r.engine = o.engine;
  const auto t0 = std::chrono::steady_clock::now();
  const double b0 = board.board_seconds(), cpu0 = thread_cpu_s();
  const auto note_times = [&] {
    r.board_s = board.board_seconds() - b0;
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.cpu_s = thread_cpu_s() - cpu0;
    r.link = link.counters();
    r.to_board = line.to_device();
    r.to_host = line.from_device();
  };
  link.connect();
  // Retries hold the link up for longer than the default period.
  link.write(br::WDOG, (1u << 24) - 1);
  machine::gains_where_missing(link, m, quiet);
  std::vector<int> axes(m.axes.size());
  for (size_t a = 0; a < axes.size(); ++a) axes[a] = int(a);
  const host::BoardState st = host::read_state(link);
  host::Vec3 at = host::enable_axes(link, axes, quiet);

  host::StreamOptions so;
  so.queue_ahead_s = m.planner.queue_ahead_s;
  if (o.telemetry)
    for (int a : axes) so.telemetry_axes |= 1u << a;
  so.ts_s = st.ts_s();

  std::vector<Plan> plans;
  while (board.board_seconds() - b0 < o.board_s) {
    if (o.stop && o.stop->load()) {
      r.stopped = true;
      break;
    }
    auto p = std::find_if(plans.begin(), plans.end(), [&](const Plan& x) { return x.start == at; });
    if (p == plans.end()) {
      Plan np;
      np.start = at;
      np.job = machine::plan_job(o.job, m, host::to_mm(at, cfg));
      for (const host::Piece& pc : np.job.pieces)
        if (!pc.action) np.sent.push_back(seg::pack(pc.seg.seg));
      if (np.sent.empty()) throw host::InputError("job", o.job, "a program that moves");
      plans.push_back(std::move(np));
      p = plans.end() - 1;
    }
    tap.clear();
    const host::StreamResult sr = host::stream_job(link, p->job.moves, p->job.pieces, cfg, so);
    // stream_job returns once the board has run every segment: the tap holds the pass.
    r.segs += tally_segments(p->sent, tap);
    r.underruns += sr.underruns;
    ++r.passes;
    at = host::start_position(link);
    note_times();
    if (o.progress) o.progress(r);
  }
  board.tap_segments(nullptr);
  const uint32_t crc = link.read(br::LINK_CRC), cmd = link.read(br::LINK_CMD);
  r.board_crc = crc & 0xFFFF;
  r.board_framing = crc >> 16;
  r.board_nak = cmd & 0xFFFF;
  r.board_dup = cmd >> 16;
  r.board_junk = link.read(br::LINK_JUNK) & 0xFFFF;
  r.fault = link.read(br::FAULT);
  host::disable_axes(link, axes, true);
  note_times();
  return r;
}

}  // namespace mc::sim
