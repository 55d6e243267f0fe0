// The link soak (issue 18): a G-code job streamed over and over to the
// in-process virtual board through a byte stream that corrupts and drops
// bytes both ways, for a set time of board time; the board's segment queue
// is tapped (VirtualBoard::tap_segments), and every segment it accepted is
// held against what the job sent: lost, doubled, reordered or never sent.
//
//   SoakOptions o;  o.job = "examples/profile.nc";  o.board_s = 3600;
//   SoakResult r = run_link_soak(default_machine(), o);
//   r.clean()  // 0 lost, doubled, reordered and foreign
//
// Deterministic for a seed: the board runs in board time, the link's
// deadlines count board time, and the faults come from seeded generators.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hls/interp_seg.hpp"
#include "host/link/board_link.hpp"
#include "host/link/serial_port.hpp"
#include "host/machine/machine_config.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::sim {

// What the board's queue took against what the host sent, segment by segment.
struct SegmentTally {
  uint64_t sent = 0;       // segments the host queued (each once)
  uint64_t applied = 0;    // segments the board's queue accepted
  uint64_t matched = 0;    // accepted once, in their place
  uint64_t lost = 0;       // sent, never accepted
  uint64_t doubled = 0;    // accepted again after their first time
  uint64_t reordered = 0;  // accepted after a later one
  uint64_t foreign = 0;    // accepted, but not a segment the host sent (a corrupt frame taken as good)
  uint64_t partial = 0;    // words left over that make no whole segment
  bool clean() const { return lost == 0 && doubled == 0 && reordered == 0 && foreign == 0 && partial == 0; }
  SegmentTally& operator+=(const SegmentTally& o);
};

// Holds the words the board's queue accepted (10 per segment) against the
// segments sent, in order. A segment that turns up where it does not belong
// is doubled when it was already taken (within the last `window` sent),
// reordered when it had been skipped, foreign otherwise; skipped segments
// never seen by the end are lost.
SegmentTally tally_segments(const std::vector<seg::Words>& sent, const std::vector<uint32_t>& applied_words,
                            size_t window = 64);

// The link's options for the soak: max_tries raised from 6, because a
// 246-byte SEG frame gets through a 1e-3 + 1e-3 line only about 60 % of the
// time (six failures in a row would end the soak every few thousand frames).
inline host::LinkOptions soak_link_options() {
  host::LinkOptions l;
  l.max_tries = 40;
  return l;
}

struct SoakResult {
  std::string job;
  BoardEngine engine = BoardEngine::Twin;
  double board_s = 0, wall_s = 0, cpu_s = 0;  // cpu_s: this thread's CPU time
  int passes = 0;
  bool stopped = false;  // ended early by `stop`
  int underruns = 0;     // times the queue ran dry while moving (retries cost board time)
  SegmentTally segs;
  host::LinkCounters link;                        // the host's view
  host::FaultInjector::Counts to_board, to_host;  // bytes offered, flipped, dropped
  // The board's own counters (16 bits, saturating at 65535): bad CRC,
  // framing errors, refused frames, duplicates, junk bytes.
  uint32_t board_crc = 0, board_framing = 0, board_nak = 0, board_dup = 0, board_junk = 0;
  uint32_t fault = 0;  // FAULT at the end
  bool clean() const { return segs.clean() && fault == 0; }
};

struct SoakOptions {
  std::string job;        // G-code file, run whole, again and again
  double board_s = 3600;  // board time to run (whole passes: the last one ends past it)
  BoardEngine engine = BoardEngine::Twin;
  double flip_rate = 1e-3;  // each byte, each way: one random bit flipped
  double drop_rate = 1e-3;  // each byte, each way: dropped
  uint32_t seed = 1;
  bool telemetry = true;  // stream telemetry as `motionctl run` does (traffic both ways)
  host::LinkOptions link = soak_link_options();
  // After each pass (for a progress line).
  std::function<void(const SoakResult&)> progress;
  // Set (from a signal handler): end after the pass under way.
  const std::atomic<bool>* stop = nullptr;
};

// Throws InputError for a bad job (file:line) or option, LinkError when the
// link gives up, BoardError when a fault stops the motion.
SoakResult run_link_soak(const MachineConfig& m, const SoakOptions& o);

}  // namespace mc::sim
