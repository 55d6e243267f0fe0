// arc_interp: the stairs-approximation circle, one iteration at a time: the
// reference for the path of rtl/interp_core.v's serial engine, used by the
// host planner's walk() and by the tests that compare the core step for step.
//
// Coordinates (x, y) are relative to the centre. D = x^2 + y^2 - R^2 is kept
// exact by adding 2*m*c + 1 when coordinate c moves by m = +-1: no multiplier
// in the loop. Each iteration moves exactly one of x, y by one count, so the
// path is 4-connected.
//
// Which one: in every quadrant the commanded direction allows one X move and
// one Y move (mx, my); one of them points away from the centre ("outward"),
// the other towards it. The paper tests the sign of D at the current point
// and breaks D = 0 arbitrarily; that walk is not the same run forwards and
// backwards. Here the test is D at the corner of the unit cell that both
// candidate moves border, (x + mx/2, y + my/2):
//   S = D + mx*x + my*y;  D(corner) = S + 1/2,  outward iff S < 0.
// It can never be zero, and the points it visits are exactly the boundary
// between lattice cells whose centres lie inside the circle and those outside:
// a set that does not depend on the direction of travel, so an arc run
// backwards retraces its points, and every point is within sqrt(2)/2 of the
// true circle (docs/numerics.md).
//
// Ending: the host gives the end point (xe, ye) and nq, the number of
// quadrant crossings before the final quadrant. In the final quadrant a
// coordinate that has reached its end value is locked, so the walk runs
// straight to the end point even when that point is not on the cell boundary
// (it must be within one step of the circle and ahead of the walk; the host
// planner checks both). N, also from the host, bounds the walk whatever it is
// given.
//
// Quadrants, with the axis points assigned so that the walk leaves a quadrant
// exactly when an inward move makes a coordinate zero:
//   ccw: Q1 x>0,y>=0  Q2 x<=0,y>0  Q3 x<0,y<=0  Q4 x>=0,y<0
//   cw:  Q1 x>=0,y>0  Q4 x>0,y<=0  Q3 x<=0,y<0  Q2 x<0,y>=0
#pragma once

#include <cstdint>

#include "interp_seg.hpp"
#include "mc_fixed.hpp"

namespace mc {

// The quadrant of (x, y) for a direction, and the two moves it allows: one
// per axis, towards minus when mxn/myn. q: 0..3 = Q1..Q4 (see the table
// above). The RTL forms the same `upper` (Q1, Q2) and `right` (Q1, Q4).
struct ArcQuadrant {
  bool operator==(const ArcQuadrant&) const = default;
  int q = 0;
  int mx = 1, my = 1;  // +1 or -1
};
inline ArcQuadrant arc_quadrant(int64_t x, int64_t y, bool ccw) {
  const bool upper = ccw ? ((x > 0 && y >= 0) || (x <= 0 && y > 0))   // Q1, Q2
                         : ((x >= 0 && y > 0) || (x < 0 && y >= 0));  // Q1, Q2
  const bool right = ccw ? ((x > 0 && y >= 0) || (x >= 0 && y < 0))   // Q1, Q4
                         : ((x >= 0 && y > 0) || (x > 0 && y <= 0));  // Q1, Q4
  ArcQuadrant a;
  a.q = upper ? (right ? 0 : 1) : (right ? 3 : 2);
  a.mx = (upper != ccw) ? 1 : -1;
  a.my = (right == ccw) ? 1 : -1;
  return a;
}

// One iteration's decision.
struct ArcStep {
  bool operator==(const ArcStep&) const = default;
  bool movex = false;    // move x (else y)
  int dir = 1;           // +1 or -1
  bool outward = false;  // |x| + |y| grows (the feed generator adds k)
  bool cross = false;    // this move leaves the quadrant
};

class ArcInterp {
 public:
  bool operator==(const ArcInterp&) const = default;
  void load(int idx, uint32_t w) {
    if (idx == seg::W_HDR) {
      ccw_ = (w >> seg::H_CCW) & 1;
      nq_ = (w >> seg::H_NQ_LSB) & 7;
      cross_ = 0;
    }
    if (idx == seg::W_A) x_ = int32_t(sext(w, seg::ARC_W));
    if (idx == seg::W_B) y_ = int32_t(sext(w, seg::ARC_W));
    if (idx == seg::W_C) xe_ = int32_t(sext(w, seg::ARC_W));
    if (idx == seg::W_D) ye_ = int32_t(sext(w, seg::ARC_W));
    if (idx == seg::W_E) d_ = int32_t(sext(w, seg::D_W));
  }

  bool final_quadrant() const { return cross_ == nq_; }
  // The end point is reached: the segment is over.
  bool fin() const { return final_quadrant() && x_ == xe_ && y_ == ye_; }

  ArcStep step() const {
    const ArcQuadrant qd = arc_quadrant(x_, y_, ccw_);
    const int mx = qd.mx, my = qd.my;
    const bool xo = x_ == 0 || ((x_ < 0) == (mx < 0));
    const int64_t s = int64_t(d_) + mx * int64_t(x_) + my * int64_t(y_);
    const bool xlock = final_quadrant() && x_ == xe_;
    const bool ylock = final_quadrant() && y_ == ye_;
    ArcStep st;
    st.movex = xlock ? false : (ylock ? true : ((s < 0) == xo));
    st.dir = st.movex ? mx : my;
    st.outward = st.movex == xo;
    const int32_t c = st.movex ? x_ : y_;
    st.cross = !st.outward && c == -st.dir;
    return st;
  }

  // Commit one iteration: st is step() of the current state.
  void iterate(const ArcStep& st) {
    int32_t& c = st.movex ? x_ : y_;
    // (c + m)^2 - c^2 = 2*m*c + 1
    d_ = int32_t(sext(uint64_t(int64_t(d_) + int64_t(2 * st.dir) * c + 1), seg::D_W));
    c = int32_t(sext(uint64_t(int64_t(c) + st.dir), seg::ARC_W));
    if (st.cross) cross_ = (cross_ + 1) & 7;
  }

  int32_t x() const { return x_; }
  int32_t y() const { return y_; }
  int32_t d() const { return d_; }
  int crossings() const { return cross_; }

 private:
  int32_t x_ = 0, y_ = 0;
  int32_t xe_ = 0, ye_ = 0;
  int32_t d_ = 0;
  int cross_ = 0;
  int nq_ = 0;
  bool ccw_ = false;
};

}  // namespace mc
