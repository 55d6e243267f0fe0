// The interpolator's segment format: what the host queues into interp_core's
// command FIFO. Mirrored by rtl/interp_seg.vh; tests/test_regs_agree.cpp
// parses that file and fails if the two disagree, so change both together.
//
// A segment is SEG_WORDS 32-bit words, always the same count whatever its type,
// so the FIFO holds whole segments and a reader can never fall out of step.
// Every motion field is relative (to the position where the segment starts),
// so the hardware never needs absolute coordinates and a segment can never
// make the command jump: each iteration moves each axis by at most one count.
//
//   word  line                 arc                        dwell
//   0     header               header                     header
//   1     N = max|d|           N (step bound)             N (iterations)
//   2     inc[31:0]            inc0[31:0]                 inc[31:0]
//   3     {0, inc[47:32]}      {k[47:32], inc0[47:32]}    {0, inc[47:32]}
//   4     |dx|                 x0 (start - centre)        -
//   5     |dy|                 y0                         -
//   6     |dz|                 xe (end - centre)          -
//   7     -                    ye                         -
//   8     -                    D0 = x0^2+y0^2-R^2         -
//   9     -                    k[31:0]                    -
//
// header: [1:0] type, [2] last (a planned stop: no underrun flag after it),
//         [3] ccw (arc), [5:4] plane (arc), [8:6] nq (arc: quadrant
//         crossings before the final quadrant), [11:9] negative x, y, z (line).
// inc is the feed generator's phase increment (iterations per clock * 2^PH_W);
// for arcs it is modulated by +-k per step (see hls/interp_core.hpp).
#pragma once

#include <array>
#include <cstdint>

namespace mc::seg {

constexpr int SEG_WORDS = 10;
constexpr int PH_W = 48;   // feed generator phase accumulator bits
constexpr int N_W = 26;    // iteration counts and line deltas (counts)
constexpr int ARC_W = 23;  // arc coordinates relative to the centre, signed
constexpr int D_W = 27;    // circle decision variable, signed
// The core runs at most one iteration per tick of 2^TICK_LOG2 clocks (its
// serial engine, hls/interp_core.hpp): inc must stay below 2^(PH_W - TICK_LOG2).
constexpr int TICK_LOG2 = 4;

// Word indices.
constexpr int W_HDR = 0;
constexpr int W_N = 1;
constexpr int W_INC_LO = 2;
constexpr int W_INC_HI = 3;
constexpr int W_A = 4;  // line |dx|, arc x0
constexpr int W_B = 5;  // line |dy|, arc y0
constexpr int W_C = 6;  // line |dz|, arc xe
constexpr int W_D = 7;  // arc ye
constexpr int W_E = 8;  // arc D0
constexpr int W_K_LO = 9;

// Header fields.
constexpr int T_LINE = 0;
constexpr int T_ARC = 1;
constexpr int T_DWELL = 2;
constexpr int H_TYPE_LSB = 0;  // 2 bits
constexpr int H_LAST = 2;
constexpr int H_CCW = 3;
constexpr int H_PLANE_LSB = 4;  // 2 bits: 0 XY, 1 ZX, 2 YZ
constexpr int H_NQ_LSB = 6;     // 3 bits
constexpr int H_NEG_LSB = 9;    // 3 bits, x in the lowest

constexpr int PLANE_XY = 0;
constexpr int PLANE_ZX = 1;
constexpr int PLANE_YZ = 2;
// Plane -> the machine axes (0 x, 1 y, 2 z) that carry the arc's x and y
// (G17, G18, G19 orientation); plane 3 is read as XY.
constexpr int PLANE_AXES[4][2] = {{0, 1}, {2, 0}, {1, 2}, {0, 1}};

constexpr uint64_t PH_MASK = (uint64_t(1) << PH_W) - 1;
constexpr uint32_t N_MASK = (uint32_t(1) << N_W) - 1;

// A segment as fields. pack() gives the words the host queues; the RTL and the
// twin pick the same fields out of the words as they are loaded.
struct Segment {
  bool operator==(const Segment&) const = default;
  int type = T_LINE;
  bool last = false;
  bool ccw = false;
  int plane = PLANE_XY;
  int nq = 0;
  int neg = 0;             // line: bit a set = axis a moves negative
  uint32_t n = 0;          // iterations (line, dwell) or step bound (arc)
  uint64_t inc = 0;        // feed phase increment (arc: at the start point)
  uint32_t d[3] = {};      // line: |dx|, |dy|, |dz|
  int32_t x0 = 0, y0 = 0;  // arc: start relative to the centre
  int32_t xe = 0, ye = 0;  // arc: end relative to the centre
  int32_t d0 = 0;          // arc: x0^2 + y0^2 - R^2
  uint64_t k = 0;          // arc: inc change per unit of |x|+|y|
};

using Words = std::array<uint32_t, SEG_WORDS>;

inline Words pack(const Segment& s) {
  Words w{};
  w[W_HDR] = uint32_t(s.type & 3) << H_TYPE_LSB | uint32_t(s.last) << H_LAST | uint32_t(s.ccw) << H_CCW |
             uint32_t(s.plane & 3) << H_PLANE_LSB | uint32_t(s.nq & 7) << H_NQ_LSB |
             uint32_t(s.neg & 7) << H_NEG_LSB;
  w[W_N] = s.n & N_MASK;
  w[W_INC_LO] = uint32_t(s.inc);
  w[W_INC_HI] = uint32_t((s.inc >> 32) & 0xFFFF) | uint32_t((s.k >> 32) & 0xFFFF) << 16;
  if (s.type == T_LINE) {
    for (int a = 0; a < 3; ++a) w[W_A + a] = s.d[a] & N_MASK;
  } else if (s.type == T_ARC) {
    w[W_A] = uint32_t(s.x0);
    w[W_B] = uint32_t(s.y0);
    w[W_C] = uint32_t(s.xe);
    w[W_D] = uint32_t(s.ye);
    w[W_E] = uint32_t(s.d0);
    w[W_K_LO] = uint32_t(s.k);
  }
  return w;
}

}  // namespace mc::seg
