// The interpolator twin (hls/interp_core.hpp and its engines) and the host
// planner: path properties over thousands of random segments, the feed, and
// the queue. The same properties are checked on the RTL in test_interp_rtl.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "hls/interp_core.hpp"
#include "interp_bench.hpp"

namespace mc::test {
namespace {

std::vector<Vec3> points(const PlannedSegment& p) {
  std::vector<Vec3> v;
  host::walk(p, [&](const Vec3& q) { v.push_back(q); });
  return v;
}

// Walk a planned segment with the twin's engines and check it like the RTL.
void check_walk(const PlannedSegment& p) {
  PathChecker chk(p.start);
  chk.expect(p);
  for (const Vec3& q : points(p)) chk.observe(q, 0);
  chk.observe(p.end, 1);
  EXPECT_EQ(chk.checked(), 1);
}

TEST(InterpTwin, ArcPropertiesOverRandomArcs) {
  SegGen g(11);
  g.max_radius = 1 << 13;  // the largest radii: FullCirclesAtTheLargestRadii
  for (int i = 0; i < 3000; ++i) {
    SCOPED_TRACE(i);
    check_walk(g.arc({0, 0, 0}));
    if (HasFailure()) return;
  }
}

TEST(InterpTwin, ArcPointsHugTheCircleWithinHalfADiagonal) {
  // On the cell boundary every point is within sqrt(2)/2 of the circle; only
  // the run onto an end point that is off that boundary may use the full step.
  SegGen g(12);
  double worst = 0;
  for (int i = 0; i < 600; ++i) {
    const int64_t r = g.irange(1, 3000);
    const double a = g.uni(0, 2 * M_PI);
    const int64_t x0 = std::llround(double(r) * std::cos(a)), y0 = std::llround(double(r) * std::sin(a));
    if (x0 == 0 && y0 == 0) continue;
    const auto p = host::plan_arc({x0, y0, 0}, {x0, y0, 0}, {0, 0}, i % 2 == 0, 1000);  // full circle
    const double r0 = std::sqrt(double(x0 * x0 + y0 * y0));
    for (const Vec3& q : points(p))
      worst = std::max(worst, std::fabs(std::hypot(double(q[0]), double(q[1])) - r0));
  }
  EXPECT_LE(worst, std::sqrt(0.5) + 1e-12);
  EXPECT_GT(worst, 0.6);  // the bound is reached, not vacuous
  std::printf("arc walk, 600 full circles up to R = 3000: worst radial deviation %.4f steps\n", worst);
}

TEST(InterpTwin, FullCirclesAtTheLargestRadii) {
  // 2^20 steps of radius, checked point by point; the core's limit, 2^22 - 2,
  // for its step count, end point and deviation.
  const int64_t r20 = int64_t(1) << 20;
  for (const bool ccw : {true, false})
    check_walk(host::plan_arc({r20, 0, 0}, {r20, 0, 0}, {0, 0}, ccw, 1000));
  const int64_t r = (int64_t(1) << 22) - 2;
  const auto p = host::plan_arc({0, -r, 0}, {0, -r, 0}, {0, 0}, false, 1000);
  EXPECT_EQ(host::arc_axis_crossing(r * r), r);
  EXPECT_EQ(p.seg.n, uint32_t(8 * r));  // 4 quadrants of 2R steps
  int64_t count = 0;
  double worst = 0;
  Vec3 last{};
  host::walk(p, [&](const Vec3& q) {
    ++count;
    last = q;
    if ((count & 255) == 0)
      worst = std::max(worst, std::fabs(std::hypot(double(q[0]), double(q[1])) - double(r)));
  });
  EXPECT_EQ(count, 8 * r + 1);
  EXPECT_EQ(last, (Vec3{0, -r, 0}));
  EXPECT_LE(worst, std::sqrt(0.5));
}

TEST(InterpTwin, ArcRunBackwardsRetracesItsPoints) {
  SegGen g(13);
  for (int i = 0; i < 1000; ++i) {
    const int64_t r = g.irange(1, 2500);
    const double a = g.uni(0, 2 * M_PI);
    const int64_t x0 = std::llround(double(r) * std::cos(a)), y0 = std::llround(double(r) * std::sin(a));
    if (x0 == 0 && y0 == 0) continue;
    const bool ccw = g.irange(0, 1) == 1;
    const auto full = points(host::plan_arc({x0, y0, 0}, {x0, y0, 0}, {0, 0}, ccw, 1000));
    // Forward from the start to a random point of the walk, then back with
    // the other direction on the same circle (same R^2, so the start of the
    // way back carries D0 = x^2 + y^2 - R^2).
    const size_t j = size_t(g.irange(1, int64_t(full.size()) - 2));
    const Vec3 e = full[j];
    const int64_t r2 = x0 * x0 + y0 * y0;
    const auto geo = host::arc_geometry(e[0], e[1], x0, y0, !ccw, r2);
    seg::Segment s;
    s.type = seg::T_ARC;
    s.ccw = !ccw;
    s.nq = geo.nq;
    s.n = uint32_t(geo.n);
    s.x0 = int32_t(e[0]);
    s.y0 = int32_t(e[1]);
    s.xe = int32_t(x0);
    s.ye = int32_t(y0);
    s.d0 = int32_t(geo.d0);
    PlannedSegment back;
    back.seg = s;
    back.start = e;
    back.end = {x0, y0, 0};
    auto rev = points(back);
    std::reverse(rev.begin(), rev.end());
    const std::vector<Vec3> fwd(full.begin(), full.begin() + long(j) + 1);
    ASSERT_EQ(rev, fwd) << "R^2 " << r2 << " start (" << x0 << ", " << y0 << ") turn at step " << j
                        << (ccw ? " ccw" : " cw");
  }
}

TEST(InterpTwin, LinePropertiesOverRandomLines) {
  SegGen g(14);
  g.max_line = 1 << 12;
  for (int i = 0; i < 4000; ++i) {
    SCOPED_TRACE(i);
    const auto p = g.line({g.irange(-1000, 1000), g.irange(-1000, 1000), g.irange(-1000, 1000)});
    check_walk(p);
    if (HasFailure()) return;
  }
}

TEST(InterpTwin, LineRunBackwardsRetracesItsPoints) {
  SegGen g(15);
  for (int i = 0; i < 3000; ++i) {
    const auto p = g.line({0, 0, 0});
    auto fwd = points(p);
    auto rev = points(host::plan_line(p.end, p.start, 1000));
    std::reverse(rev.begin(), rev.end());
    ASSERT_EQ(fwd, rev) << "to (" << p.end[0] << ", " << p.end[1] << ", " << p.end[2] << ")";
  }
}

TEST(InterpTwin, ArcStepCountMatchesThePaperForAQuarter) {
  // The paper's quarter circle: N = |X0 - Xf| + |Y0 - Yf| = 2R.
  for (int64_t r = 1; r < 300; ++r) {
    const auto p = host::plan_arc({r, 0, 0}, {0, r, 0}, {0, 0}, true, 1000);
    EXPECT_EQ(p.seg.n, uint32_t(2 * r));
    EXPECT_EQ(points(p).size(), size_t(2 * r + 1));
  }
}

// The message a planner call throws, or "no error".
std::string msg(const std::function<void()>& f) {
  try {
    f();
  } catch (const host::InputError& e) {
    return std::string(e.what());
  }
  return std::string("no error");
}

TEST(InterpPlan, BadGeometryIsAClearError) {
  EXPECT_NE(msg([] {
              host::plan_arc({0, 0, 0}, {1, 0, 0}, {0, 0}, true, 1000);
            }).find("zero radius"),
            std::string::npos);
  EXPECT_NE(msg([] {
              host::plan_arc({100, 0, 0}, {0, 102, 0}, {0, 0}, true, 1000);
            }).find("off the circle"),
            std::string::npos);
  EXPECT_NE(msg([] {
              host::plan_arc({100, 0, 0}, {0, 100, 5}, {0, 0}, true, 1000);
            }).find("helical"),
            std::string::npos);
  EXPECT_NE(msg([] {
              host::plan_arc({1 << 23, 0, 0}, {0, 1 << 23, 0}, {0, 0}, true, 1000);
            }).find("too far from the centre"),
            std::string::npos);
  EXPECT_NE(msg([] {
              host::plan_arc({100, 0, 0}, {0, 100, 0}, {0, 0}, true, 1e8);
            }).find("feed too high"),
            std::string::npos);
  EXPECT_NE(msg([] { host::plan_line({0, 0, 0}, {10, 0, 0}, -1); }).find("feed"), std::string::npos);
  EXPECT_NE(msg([] {
              host::plan_line({0, 0, 0}, {1 << 27, 0, 0}, 1000);
            }).find("split the move"),
            std::string::npos);
  // Within one step of the circle but behind the walk in one axis: the walk
  // enters Q1 at (1000, 0) and only decreases x from there.
  EXPECT_NE(msg([] {
              host::plan_arc({0, 1000, 0}, {1001, 0, 0}, {0, 0}, true, 1000);
            }).find("behind"),
            std::string::npos);
}

// --- The cycle twin ------------------------------------------------------

// A host that keeps the twin's queue fed from a list of planned segments.
struct TwinRig {
  InterpCore<9> core;
  InterpIn in;
  uint64_t clocks = 0;
  TwinRig() { core.reset(); }

  void clock() {
    core.clock(in);
    ++clocks;
    in = InterpIn{};
  }
  Vec3 pos() const { return {core.pos(0), core.pos(1), core.pos(2)}; }
  // Queue one segment, a word per clock; returns whether the core had room.
  bool push(const PlannedSegment& p, PathChecker* chk) {
    const bool room = core.count() <= InterpCore<9>::DEPTH - seg::SEG_WORDS;
    const seg::Words w = seg::pack(p.seg);
    for (uint32_t word : w) {
      in.wr = true;
      in.wdata = word;
      clock();
      if (chk) chk->observe(pos(), core.seg_cnt());
    }
    if (room && chk) chk->expect(p);
    return room;
  }
};

TEST(InterpCoreTwin, RandomSegmentsRunInOrderWithAllProperties) {
  SegGen g(21);
  TwinRig rig;
  PathChecker chk({0, 0, 0});
  Vec3 at{0, 0, 0};
  for (int i = 0; i < 600; ++i) {
    const auto p = g.any(at);
    at = p.end;
    ASSERT_TRUE(rig.push(p, &chk));
    // Let the queue drain now and then, so that both full and empty queues
    // are seen.
    const int keep = (i / 50) % 2 ? 30 : 2;
    while (rig.core.count() >= keep * seg::SEG_WORDS) {
      rig.clock();
      chk.observe(rig.pos(), rig.core.seg_cnt());
    }
  }
  while (rig.core.busy() || rig.core.count() > 0) {
    rig.clock();
    chk.observe(rig.pos(), rig.core.seg_cnt());
  }
  EXPECT_EQ(chk.checked(), 600);
  EXPECT_GT(chk.steps(), 600 * 50);
  EXPECT_EQ(chk.pending(), 0u);
  EXPECT_EQ(rig.pos(), at);
  EXPECT_FALSE(rig.core.ovf());
}

// Runs a long line along x from the origin: after any number of clocks
// exactly floor(clocks * inc / 2^48) iterations have fired, less the ones
// still due or in the pipeline (at most two). Returns the clocks run.
uint64_t expect_no_drift(TwinRig& rig, const PlannedSegment& p, int rounds, int clocks) {
  rig.push(p, nullptr);
  while (rig.core.state() != InterpCore<9>::ST_RUN) rig.clock();
  const uint64_t t0 = rig.clocks;
  const long double inc = static_cast<long double>(p.seg.inc);
  for (int i = 0; i < rounds; ++i) {
    for (int k = 0; k < clocks; ++k) rig.clock();
    const long double expect = std::floor((rig.clocks - t0) * inc / 281474976710656.0L);
    const long double got = rig.core.pos(0);
    EXPECT_LE(expect - got, 2) << "after " << rig.clocks - t0 << " clocks";
    EXPECT_GE(expect - got, 0);
  }
  return rig.clocks - t0;
}

TEST(InterpCoreTwin, LineRateIsExactWithNoDrift) {
  // A long line at an awkward rate.
  TwinRig rig;
  const auto p = host::plan_line({0, 0, 0}, {3000000, 1234567, 0}, 123456.789);
  expect_no_drift(rig, p, 5, 2000000);
  // The feed itself: the iteration rate times the path per iteration.
  const double rate = double(p.seg.inc) / 281474976710656.0 * kClk;
  EXPECT_NEAR(rate * p.length / double(p.seg.n), 123456.789, 123456.789 * 1e-9);
}

// Worst relative speed error over each 1/64 of a full circle of radius r run
// by the cycle twin, from the clock at which each point was reached.
double arc_speed_error(const PlannedSegment& p, int64_t r, double feed, double* total_s) {
  TwinRig rig;
  rig.in.set = 7;
  rig.in.set_pos[0] = int32_t(r);
  rig.clock();
  rig.push(p, nullptr);
  std::vector<std::pair<uint64_t, Vec3>> at;
  Vec3 last = rig.pos();
  while (rig.core.seg_cnt() == 0) {
    rig.clock();
    if (rig.pos() != last) {
      last = rig.pos();
      at.emplace_back(rig.clocks, last);
    }
  }
  const size_t w = at.size() / 64;
  double worst = 0;
  for (size_t i = 0; i + w < at.size(); i += w) {
    const auto& a = at[i].second;
    const auto& b = at[i + w].second;
    const double ang = std::remainder(
        std::atan2(double(b[1]), double(b[0])) - std::atan2(double(a[1]), double(a[0])), 2 * M_PI);
    const double v = std::fabs(ang) * double(r) / (double(at[i + w].first - at[i].first) / kClk);
    worst = std::max(worst, std::fabs(v / feed - 1));
  }
  *total_s = double(at.back().first - at.front().first) / kClk;
  return worst;
}

TEST(InterpCoreTwin, ArcTangentialSpeedIsTheFeedAllRound) {
  // Modulating the rate by |x|+|y| keeps the speed at the feed everywhere;
  // the paper's constant rate (corrected eq. 3, f0 = 4 V / pi) is right only
  // on average over a quadrant.
  const int64_t r = 20000;
  const double feed = 250000;  // counts/s
  const auto p = host::plan_arc({r, 0, 0}, {r, 0, 0}, {0, 0}, true, feed);
  double total = 0;
  const double modulated = arc_speed_error(p, r, feed, &total);
  EXPECT_LT(modulated, 0.003) << "worst speed error over 1/64 of the circle";
  EXPECT_NEAR(total, 2 * M_PI * double(r) / feed, 2 * M_PI * double(r) / feed * 1e-3);
  PlannedSegment flat = p;
  flat.seg.k = 0;
  flat.seg.inc = uint64_t(std::llround(4 * feed / M_PI / kClk * 281474976710656.0));
  double flat_total = 0;
  const double constant = arc_speed_error(flat, r, feed, &flat_total);
  EXPECT_GT(constant, 0.2);
  EXPECT_NEAR(flat_total, total, total * 2e-3);  // same average: the corrected eq. 3
  std::printf("arc speed over 1/64 circle, worst error: modulated %.4f%%, constant 4V/pi rate %.1f%%\n",
              100 * modulated, 100 * constant);
}

TEST(InterpCoreTwin, UnderrunHoldsPositionAndFlags) {
  TwinRig rig;
  auto a = host::plan_line({0, 0, 0}, {50, 20, 0}, 5e5);
  rig.push(a, nullptr);
  for (int i = 0; i < 2000; ++i) rig.clock();
  EXPECT_TRUE(rig.core.underrun());
  EXPECT_EQ(rig.pos(), (Vec3{50, 20, 0}));
  for (int i = 0; i < 1000; ++i) rig.clock();
  EXPECT_EQ(rig.pos(), (Vec3{50, 20, 0}));  // holds, never jumps
  rig.in.clr = true;
  rig.clock();
  EXPECT_FALSE(rig.core.underrun());
  // A segment marked last ends the program: no underrun.
  auto b = host::plan_line({50, 20, 0}, {0, 0, 0}, 5e5);
  b.seg.last = true;
  rig.push(b, nullptr);
  for (int i = 0; i < 2000; ++i) rig.clock();
  EXPECT_EQ(rig.pos(), (Vec3{0, 0, 0}));
  EXPECT_FALSE(rig.core.underrun());
}

TEST(InterpCoreTwin, OverflowDropsWholeSegmentsAndKeepsStep) {
  TwinRig rig;
  rig.in.hold = true;  // nothing drains while we overfill
  PathChecker chk({0, 0, 0});
  Vec3 at{0, 0, 0};
  int admitted = 0, dropped = 0;
  std::vector<PlannedSegment> kept;
  for (int i = 0; i < 60; ++i) {
    Vec3 to = at;
    to[0] += 3;
    to[1] += i % 3;
    const auto p = host::plan_line(at, to, 5e5);
    const bool room = rig.core.count() <= InterpCore<9>::DEPTH - seg::SEG_WORDS;
    const seg::Words w = seg::pack(p.seg);
    for (uint32_t word : w) {
      rig.in.hold = true;
      rig.in.wr = true;
      rig.in.wdata = word;
      rig.clock();
    }
    if (room) {
      ++admitted;
      kept.push_back(p);
      at = to;
    } else {
      ++dropped;
    }
  }
  // What the queue holds, and one more: the core loads the first segment
  // (into its engines) even while the feed is held.
  EXPECT_EQ(admitted, InterpCore<9>::DEPTH / seg::SEG_WORDS + 1);
  EXPECT_EQ(dropped, 60 - admitted);
  EXPECT_TRUE(rig.core.ovf());
  for (const auto& p : kept) chk.expect(p);
  while (rig.core.busy() || rig.core.count() > 0) {
    rig.clock();
    chk.observe(rig.pos(), rig.core.seg_cnt());
  }
  EXPECT_EQ(chk.checked(), admitted);
  EXPECT_EQ(rig.pos(), at);
}

TEST(InterpCoreTwin, HoldAbortAndSet) {
  TwinRig rig;
  const auto p = host::plan_line({0, 0, 0}, {1000, 0, 0}, 1e5);
  rig.push(p, nullptr);
  for (int i = 0; i < 60000; ++i) rig.clock();
  const Vec3 mid = rig.pos();
  EXPECT_GT(mid[0], 0);
  EXPECT_LT(mid[0], 1000);
  for (int i = 0; i < 60000; ++i) {
    rig.in.hold = true;
    rig.clock();
  }
  EXPECT_EQ(rig.pos(), mid);  // feed hold: not one count more
  // set is refused while a segment runs...
  rig.in.set = 7;
  rig.in.set_pos[0] = 77;
  rig.clock();
  EXPECT_NE(rig.pos()[0], 77);
  // ...abort stops at once, empties the queue, keeps the position...
  rig.push(p, nullptr);
  rig.in.abort = true;
  rig.clock();
  const Vec3 stop = rig.pos();
  for (int i = 0; i < 100000; ++i) rig.clock();
  EXPECT_EQ(rig.pos(), stop);
  EXPECT_EQ(rig.core.count(), 0);
  EXPECT_FALSE(rig.core.busy());
  // ...and set is taken once idle.
  rig.in.set = 7;
  rig.in.set_pos[0] = -5;
  rig.in.set_pos[1] = 6;
  rig.in.set_pos[2] = 7;
  rig.clock();
  EXPECT_EQ(rig.pos(), (Vec3{-5, 6, 7}));
  // Each strobe bit loads its own axis only, as the board loads them one at
  // a time from one register value.
  for (int a = 0; a < 3; ++a) {
    rig.in.set = uint8_t(1u << a);
    rig.in.set_pos[0] = rig.in.set_pos[1] = rig.in.set_pos[2] = 100 + a;
    rig.clock();
  }
  rig.in.set = 0;
  rig.clock();
  EXPECT_EQ(rig.pos(), (Vec3{100, 101, 102}));
}

TEST(InterpCoreTwin, SegmentsRunBackToBackWithoutAStop) {
  // Two lines at an iteration rate of one per 20 clocks: the junction costs
  // at most the end test, load and preparation (JUNCTION), and no iteration
  // is lost over the pair.
  TwinRig rig;
  const double feed = kClk / 20;
  const auto a = host::plan_line({0, 0, 0}, {400, 0, 0}, feed);
  const auto b = host::plan_line({400, 0, 0}, {800, 0, 0}, feed);
  rig.push(a, nullptr);
  rig.push(b, nullptr);
  std::vector<uint64_t> t;
  int64_t last = 0;
  while (rig.core.seg_cnt() < 2) {
    rig.clock();
    if (rig.core.pos(0) != last) {
      last = rig.core.pos(0);
      t.push_back(rig.clocks);
    }
  }
  ASSERT_EQ(t.size(), 800u);
  uint64_t worst = 0;
  for (size_t i = 1; i < t.size(); ++i) worst = std::max(worst, t[i] - t[i - 1]);
  constexpr int kJunction = InterpCore<9>::JUNCTION;
  EXPECT_LE(worst, uint64_t(kJunction)) << "largest gap between steps, clocks";
  EXPECT_NEAR(double(t.back() - t.front()), 799 * 20.0, kJunction);
}

TEST(InterpCoreTwin, TheHighestRateRunsOneIterationPerTickWithoutLoss) {
  // The planner's highest feed: one iteration per TICK clocks. Every fire of
  // the phase accumulator runs; after any number of clocks exactly
  // floor(clocks * inc / 2^48) iterations have fired, less at most the ones
  // still in the pipeline.
  constexpr int kTick = InterpCore<9>::TICK;
  const double top = host::max_iteration_rate(kClk) * (1 - 1e-9);
  const auto p = host::plan_line({0, 0, 0}, {4000000, 0, 0}, top);
  EXPECT_LT(p.seg.inc, uint64_t(1) << (seg::PH_W - seg::TICK_LOG2));
  EXPECT_GT(p.seg.inc, (uint64_t(1) << (seg::PH_W - seg::TICK_LOG2)) - 100000);
  TwinRig rig;
  const uint64_t clocks = expect_no_drift(rig, p, 4, 3000000);
  EXPECT_NEAR(double(rig.core.pos(0)), double(clocks) / kTick, 2.0);
  // Above it the planners refuse, with the limit in the message.
  const double over = host::max_iteration_rate(kClk) * 1.001;
  EXPECT_NE(msg([&] {
              host::plan_line({0, 0, 0}, {1000, 0, 0}, over);
            }).find("feed too high"),
            std::string::npos);
  EXPECT_NE(msg([&] {
              host::plan_line({0, 0, 0}, {1000, 0, 0}, over);
            }).find("750000 iterations/s"),
            std::string::npos);
  EXPECT_NE(msg([&] {
              host::plan_arc({1000, 0, 0}, {0, 1000, 0}, {0, 0}, true, over / std::sqrt(2.0));
            }).find("feed too high"),
            std::string::npos);
  EXPECT_NO_THROW(host::plan_arc({1000, 0, 0}, {0, 1000, 0}, {0, 0}, true, 0.99 * top / std::sqrt(2.0)));
}

}  // namespace
}  // namespace mc::test
