#include "host/motion/job_stream.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
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

std::string line_of(const std::vector<Move>& moves, const std::vector<Piece>& p, size_t i) {
  if (i >= p.size()) return "the end of the job";
  return "line " + std::to_string(moves[size_t(p[i].move)].line);
}

}  // namespace

StreamResult stream_job(BoardLink& l, const std::vector<Move>& moves, const std::vector<Piece>& input,
                        const PlannerConfig& cfg, const StreamOptions& o) {
  StreamResult r;
  std::vector<Piece> pieces = input;
  uint32_t decim = o.telemetry_decim;
  if (o.telemetry_axes && decim == 0) {
    if (!(o.ts_s > 0)) throw InputError("sample period", format_number(o.ts_s) + " s", "above 0");
    int n = 0;
    for (unsigned m = o.telemetry_axes; m; m >>= 1) n += int(m & 1);
    const double baud = double(l.read(br::BAUD));
    // A frame plus the replies to the requests of one round of the loop.
    const double busy_s = 10.0 * (telemetry_frame_bytes(n) + 4 * kReplyBytes) / baud;
    decim = uint32_t(std::max(1.0, std::ceil(busy_s / o.ts_s)));
  }
  TelemetryLog tlm(l, o.telemetry_axes, decim);

  const uint32_t segs0 = l.read(br::IP_SEGS) & 0xFFFF;
  l.write(br::IP_CTRL, 1u << bb::I_CLR);
  std::vector<size_t> sent_piece;  // the piece of each segment sent, in order
  size_t next = 0;                 // the next piece to send
  size_t done = 0;                 // segments the board has finished
  bool stopping = false;
  size_t shown = size_t(-1);

  for (;;) {
    if (o.stop && o.stop->load() && !stopping) {
      stopping = true;
      r.stopped = true;
      // The queued tail keeps running; after it, a stop at the limit along
      // the path instead of the rest of the job.
      std::vector<Piece> tail;
      if (!sent_piece.empty()) tail = stop_after(moves, pieces, sent_piece.back(), cfg);
      pieces.resize(next);
      pieces.insert(pieces.end(), tail.begin(), tail.end());
      r.stopped_at_line = pieces.empty() ? 0 : moves[size_t(pieces.back().move)].line;
    }
    // Feed the queue up to the planned time ahead.
    while (next < pieces.size()) {
      if (pieces[next].action) {
        if (done < sent_piece.size()) break;  // let the queue drain first
        if (l.read(br::IP_STAT) & (1u << bb::IS_BUSY)) break;
        if (o.action) o.action(moves[size_t(pieces[next].move)]);
        ++next;
        continue;
      }
      // Planned time queued: from the start of the first piece not done to
      // the end of the last one sent.
      if (done < sent_piece.size()) {
        const Piece& first = pieces[sent_piece[done]];
        const double queued = pieces[sent_piece.back()].t_end - (first.t_end - first.seg.duration);
        if (queued >= o.queue_ahead_s && sent_piece.size() - done >= 2) break;
      }
      std::vector<seg::Words> batch;
      size_t k = next;
      while (k < pieces.size() && !pieces[k].action && batch.size() < kBatch)
        batch.push_back(seg::pack(pieces[k++].seg.seg));
      if (!l.segments(batch)) break;  // FULL: the board takes them later
      for (size_t i = next; i < k; ++i) sent_piece.push_back(i);
      next = k;
    }
    // What the board has done.
    const uint32_t stat = l.read(br::IP_STAT);
    const uint32_t fault = l.read(br::FAULT);
    done = size_t((l.read(br::IP_SEGS) - segs0) & 0xFFFF);
    // IP_SEGS is 16 bits: unwrap against what was sent.
    while (done + 0x10000 <= sent_piece.size()) done += 0x10000;
    done = std::min(done, sent_piece.size());
    if (stat & (1u << bb::IS_UNDERRUN)) {
      ++r.underruns;
      l.write(br::IP_CTRL, 1u << bb::I_CLR);
    }
    tlm.drain(r);
    if (fault)
      throw BoardError("motion stopped by a fault at " +
                       line_of(moves, pieces, done < sent_piece.size() ? sent_piece[done] : pieces.size()) +
                       ": " + fault_names(fault));
    const size_t running = done < sent_piece.size() ? sent_piece[done] : next;
    if (o.progress && running != shown) {
      o.progress(running);
      shown = running;
    }
    const bool busy = stat & (1u << bb::IS_BUSY);
    if (next >= pieces.size() && done >= sent_piece.size() && !busy) break;
    l.poll(std::chrono::milliseconds(1));
  }
  tlm.drain(r);
  r.gaps = tlm.gaps();
  r.segments = sent_piece.size();
  r.planned_s = pieces.empty() ? 0 : pieces.back().t_end;
  return r;
}

}  // namespace mc::host
