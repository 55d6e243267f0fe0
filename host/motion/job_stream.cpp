#include "host/motion/job_stream.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "host/base/errors.hpp"
#include "host/link/board_capture.hpp"
#include "host/link/board_state.hpp"
#include "host/link/protocol.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

namespace {

constexpr size_t kBatch = 6;  // segments per SEG frame (the frame's most)

class TelemetryLog {
 public:
  TelemetryLog(BoardLink& l, unsigned mask, uint32_t decim) : l_(l), mask_(mask), unwrap_(mask, decim) {
    if (!mask_) return;
    l_.write(br::TLM, 0);
    l_.telemetry().clear();
    l_.write(br::TLM, decim << bb::T_DECIM_LSB | mask_ << bb::T_AXES_LSB);
  }
  ~TelemetryLog() {
    if (!mask_) return;
    try {
      l_.write(br::TLM, 0);
    } catch (...) {  // the link is gone; the watchdog turns the drives off anyway
    }
  }
  int64_t gaps() const { return unwrap_.gaps(); }
  TelemetryLog(const TelemetryLog&) = delete;
  TelemetryLog& operator=(const TelemetryLog&) = delete;

  void drain(StreamResult& r) {
    auto& q = l_.telemetry();
    while (!q.empty()) {
      const proto::Frame f = std::move(q.front());
      q.pop_front();
      if (!mask_) continue;
      proto::Telemetry t;
      JobSample s;
      if (!unwrap_.take(f, t, s.n)) continue;
      for (const proto::AxisSample& a : t.axes) {
        s.pos[size_t(a.axis)] = a.pos;
        s.cmd[size_t(a.axis)] = a.cmd;
      }
      r.samples.push_back(s);
    }
  }

 private:
  BoardLink& l_;
  unsigned mask_;
  TelemetryUnwrap unwrap_;
};

}  // namespace

JobStreamer::JobStreamer(BoardLink& l, const PlannerConfig& cfg, const Vec3& at, double queue_ahead_s)
    : l_(l), cfg_(cfg), ahead_s_(queue_ahead_s), at_(at) {
  segs_base_ = l_.read(br::IP_SEGS) & 0xFFFF;
  l_.write(br::IP_CTRL, 1u << bb::I_CLR);
}

void JobStreamer::load(const std::vector<Move>& moves, const std::vector<Piece>& pieces) {
  if (!drained()) throw std::logic_error("JobStreamer::load while segments are queued");
  drop_queue();
  orig_ = plan_ = moves;
  pieces_ = pieces;
  if (!pieces.empty()) t_ = pieces.front().t_end - pieces.front().seg.duration;
}

void JobStreamer::append(const std::vector<Move>& moves) {
  if (moves.empty()) return;
  orig_.insert(orig_.end(), moves.begin(), moves.end());
  // Detached (a stop's tail under way): planned once the tail is out.
  if (attached_) replan();
}

Vec3d JobStreamer::end() const {
  return orig_.empty() ? to_mm(at_, cfg_) : orig_.back().end;
}

void JobStreamer::drop_queue() {
  orig_.clear();
  plan_.clear();
  pieces_.clear();
  next_ = 0;
  attached_ = true;
  hold_ = false;
  last_.reset();
  flight_.clear();
  v_ = 0;
}

void JobStreamer::rebase() {
  if (!last_) return;
  const size_t mi = size_t(last_->piece.move);
  std::vector<Move> rest;
  v_ = 0;
  if (last_->move.is_motion()) {
    Piece p = last_->piece;
    p.move = 0;
    const PathPoint pe = piece_end({last_->move}, p, cfg_);
    v_ = pe.v;
    const Move& m = orig_[mi];
    if (pe.s < m.length - 1e-9) rest.push_back(sub_move(m, pe.s, m.length));
  }
  rest.insert(rest.end(), orig_.begin() + long(mi) + 1, orig_.end());
  orig_ = std::move(rest);
  at_ = last_->piece.seg.end;
  t_ = last_->piece.t_end;
  last_.reset();
}

void JobStreamer::replan() {
  rebase();
  plan_ = orig_;
  plan_speeds(plan_, cfg_, feed_, rapid_, v_);
  if (!plan_.empty() && plan_[0].is_motion() && v_ > plan_[0].v_nominal * (1 + 1e-9)) {
    // The feed went down under the machine: first slow to the new feed at
    // the limit along the path (those parts keep the speed they carry),
    // then the rest at it.
    std::vector<size_t> src;
    std::vector<Move> lead = slow_down(plan_, PathPoint{0, 0, v_}, plan_[0].v_nominal, &src);
    if (!lead.empty()) {
      for (Move& m : lead) {
        m.v_nominal = m.v_entry;
        m.no_override = true;
        m.rapid = m.exact_stop = false;
      }
      const size_t j = src.back();
      const double s_to = lead.back().length;  // every part after the first starts at its move's start
      std::vector<Move> rest = std::move(lead);
      if (s_to < orig_[j].length - 1e-9) rest.push_back(sub_move(orig_[j], s_to, orig_[j].length));
      rest.insert(rest.end(), orig_.begin() + long(j) + 1, orig_.end());
      orig_ = std::move(rest);
      plan_ = orig_;
      plan_speeds(plan_, cfg_, feed_, rapid_, v_);
    }
  }
  pieces_ = chop_from(plan_, cfg_, at_, t_);
  next_ = 0;
}

void JobStreamer::hold() {
  if (hold_) return;
  hold_ = true;
  if (!attached_) return;  // a stop is under way already
  replan();
  std::vector<Piece> tail;
  if (v_ > 1e-9 && !plan_.empty()) {
    std::vector<size_t> src;
    const std::vector<Move> parts = slow_down(plan_, PathPoint{0, 0, v_}, 0, &src);
    tail = chop_from(parts, cfg_, at_, t_);
    for (Piece& p : tail) p.move = int(src[size_t(p.move)]);
    if (!parts.empty()) {
      // What is left after the stop: from where the last part ends.
      const size_t j = src.back();
      const double s_to = parts.back().length;
      std::vector<Move> rest;
      if (s_to < orig_[j].length - 1e-9) rest.push_back(sub_move(orig_[j], s_to, orig_[j].length));
      rest.insert(rest.end(), orig_.begin() + long(j) + 1, orig_.end());
      orig_ = std::move(rest);
      if (!tail.empty()) {
        at_ = tail.back().seg.end;
        t_ = tail.back().t_end;
      }
    }
  }
  v_ = 0;
  pieces_ = std::move(tail);
  next_ = 0;
  attached_ = false;
}

void JobStreamer::resume() {
  hold_ = false;  // send() plans the rest once the stop's tail is out
}

void JobStreamer::stop() {
  hold();
  orig_.clear();
  hold_ = false;
}

void JobStreamer::set_overrides(double feed, double rapid) {
  if (feed == feed_ && rapid == rapid_) return;
  feed_ = feed;
  rapid_ = rapid;
  if (attached_) replan();
}

Vec3 JobStreamer::abort() {
  Vec3 at = abort_interpolator(l_);
  for (size_t k = 0; k < 3; ++k)
    if (!cfg_.axes[k].present) at[k] = 0;  // as the plan has them
  restart(at);
  return at;
}

void JobStreamer::restart(const Vec3& at) {
  drop_queue();
  at_ = at;
  segs_base_ = l_.read(br::IP_SEGS) & 0xFFFF;
  sent_ = done_ = 0;
  busy_ = false;
}

JobStreamer::State JobStreamer::state() const {
  if (hold_) return flight_.empty() && !busy_ && next_ >= pieces_.size() ? State::held : State::holding;
  return drained() ? State::idle : State::run;
}

bool JobStreamer::drained() const {
  return flight_.empty() && !busy_ && next_ >= pieces_.size() && (attached_ || orig_.empty());
}

Vec3 JobStreamer::command_end() const {
  return last_ ? last_->piece.seg.end : at_;
}

std::optional<JobStreamer::Running> JobStreamer::current() const {
  if (!flight_.empty()) return flight_.front().what;
  if (next_ < pieces_.size()) {
    const Move& m = plan_[size_t(pieces_[next_].move)];
    return Running{m.line, m.no_override, pieces_[next_].t_end, 0};
  }
  if (!attached_ && !orig_.empty()) return Running{orig_.front().line, orig_.front().no_override, t_, 0};
  return std::nullopt;
}

void JobStreamer::record(const Piece& p, const Move& m) {
  if (!p.action) {
    double cpm = 0;  // the path's scale: the axes share one on a sane machine
    for (const AxisLimits& a : cfg_.axes)
      if (a.present && cpm == 0) cpm = a.counts_per_mm;
    const bool moves = p.seg.seg.type != seg::T_DWELL && p.seg.duration > 0 && cpm > 0;
    const double feed = moves ? p.seg.length / p.seg.duration / cpm : 0;
    flight_.push_back(Flight{Running{m.line, m.no_override, p.t_end, feed}, p.t_end - p.seg.duration});
    ++sent_;
    ++segments_;
  }
  last_line_ = m.line;
  t_sent_ = p.t_end;
  if (attached_) last_ = Sent{m, p};
}

void JobStreamer::poll() {
  const uint32_t stat = l_.read(br::IP_STAT);
  fault_ = l_.read(br::FAULT);
  // IP_SEGS is 16 bits: unwrap against what was sent.
  uint64_t done = (l_.read(br::IP_SEGS) - segs_base_) & 0xFFFF;
  while (done + 0x10000 <= sent_) done += 0x10000;
  done = std::min(done, sent_);
  for (; done_ < done; ++done_) flight_.pop_front();
  busy_ = stat & (1u << bb::IS_BUSY);
  if (stat & (1u << bb::IS_UNDERRUN)) {
    ++underruns_;
    l_.write(br::IP_CTRL, 1u << bb::I_CLR);
  }
  if (fault_) {
    const std::string where = flight_.empty() ? (next_ < pieces_.size() ? "line " + std::to_string(last_line_)
                                                                        : std::string("the end of the job"))
                                              : "line " + std::to_string(flight_.front().what.line);
    drop_queue();
    throw BoardError("motion stopped by a fault at " + where + ": " + fault_names(fault_));
  }
  send();
}

void JobStreamer::send() {
  if (!attached_ && next_ >= pieces_.size() && !hold_) {
    // The stop's tail is out: what was kept runs from where it ends.
    attached_ = true;
    replan();
  }
  while (next_ < pieces_.size()) {
    const Piece& p = pieces_[next_];
    if (p.action) {
      if (!flight_.empty() || busy_) break;  // the queue drains first
      const Move m = plan_[size_t(p.move)];
      record(p, m);
      ++next_;
      if (on_action) on_action(m);
      continue;
    }
    // Planned time queued: from the start of the first piece not done to
    // the end of the last one sent. Of that first piece at most the longest
    // motion piece counts: a long dwell must not, or the queue behind it is
    // one short ramp piece when it ends and the board runs dry.
    const double from =
        flight_.empty() ? p.t_end - p.seg.duration
                        : std::max(flight_.front().t_start, flight_.front().what.t_end - cfg_.max_piece_s);
    if (flight_.size() >= 2 && flight_.back().what.t_end - from >= ahead_s_) break;
    // A batch stops at the planned time too: a hold waits for what is queued.
    std::vector<seg::Words> batch;
    size_t k = next_;
    while (k < pieces_.size() && !pieces_[k].action && batch.size() < kBatch &&
           (batch.size() < 2 || pieces_[k - 1].t_end - from < ahead_s_))
      batch.push_back(seg::pack(pieces_[k++].seg.seg));
    if (!l_.segments(batch)) break;  // FULL: the board takes them later
    for (; next_ < k; ++next_) record(pieces_[next_], plan_[size_t(pieces_[next_].move)]);
  }
}

StreamResult stream_job(BoardLink& l, const std::vector<Move>& moves, const std::vector<Piece>& pieces,
                        const PlannerConfig& cfg, const StreamOptions& o) {
  StreamResult r;
  uint32_t decim = o.telemetry_decim;
  if (o.telemetry_axes && decim == 0) {
    if (!(o.ts_s > 0)) throw InputError("sample period", format_number(o.ts_s) + " s", "above 0");
    int n = 0;
    for (unsigned m = o.telemetry_axes; m; m >>= 1) n += int(m & 1);
    // A frame plus the replies to the requests of one round of the loop.
    decim = telemetry_decimation(l, o.ts_s, 4, n);
  }
  if (moves.empty()) return r;
  TelemetryLog tlm(l, o.telemetry_axes, decim);
  JobStreamer s(l, cfg, to_counts(moves.front().start, cfg), o.queue_ahead_s);
  s.on_action = o.action;
  s.load(moves, pieces);
  double shown = -1;
  for (;;) {
    if (o.stop && o.stop->load() && !r.stopped) {
      // The queued tail keeps running; after it, a stop at the limit along
      // the path instead of the rest of the job.
      r.stopped = true;
      s.stop();
    }
    s.poll();
    tlm.drain(r);
    if (const auto c = s.current(); c && o.progress && c->t_end != shown) {
      o.progress(c->t_end, c->line);
      shown = c->t_end;
    }
    if (s.drained()) break;
    l.poll(std::chrono::milliseconds(1));
  }
  tlm.drain(r);
  r.gaps = tlm.gaps();
  r.segments = s.segments();
  r.underruns = s.underruns();
  r.planned_s = s.planned_s();
  if (r.stopped) r.stopped_at_line = s.last_line();
  return r;
}

}  // namespace mc::host
