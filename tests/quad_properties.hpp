// quad_decoder properties, as a typed GoogleTest suite: instantiated on the
// twin alone (test_quad_decoder_twin, fast) and on the C/RTL co-simulation
// (test_quad_decoder_rtl, where every clock is also compared bit for bit).
// The expected values come from the generated waveform's true count and the
// documented semantics, never from the twin.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "quad_harness.hpp"

namespace mc::test {

template <typename Sim>
class QuadProperties : public ::testing::Test {
 protected:
  using Twin = typename Sim::TwinT;
  using Bench = QuadBench<Sim>;
  static constexpr uint32_t kErrMax = ones(Twin::err_w);
  static constexpr int64_t kVelMax = smax(Twin::vel_w);
  static constexpr int64_t kVelMin = smin(Twin::vel_w);
  static constexpr uint32_t kAgeMax = ones(Twin::age_w);

  std::mt19937_64 rng{20261122};
  double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }

  // The clock (a QuadBench::now value) at whose edge a pin change at time t
  // reaches the filtered levels: the edge at ceil(t) samples it,
  // max(filt_len, 1) + 1 edges later it is out (rtl/quad_decoder.v). t must
  // be clear of the metastable window.
  static uint64_t level_clock_of(const Bench& b, double t) {
    return uint64_t(std::ceil(t)) + uint64_t(std::max<int>(int(b.in.filt_len), 1)) + 1;
  }
  // ... and the counters (pos_o, the index latch, the error flag): one edge
  // later, the filter's decision being registered before them.
  static uint64_t clock_of(const Bench& b, double t) { return level_clock_of(b, t) + 1; }
  static void run_to(Bench& b, uint64_t k) {
    while (b.now < k) b.clock();
  }
  // The decoder's count since `base`, and the waveform's, in 32-bit arithmetic.
  static int32_t moved(const Bench& b, int32_t base) { return int32_t(uint32_t(b.out.pos) - uint32_t(base)); }
  static int32_t truth_since(const Bench& b, int64_t base) {
    return int32_t(uint32_t(uint64_t(b.wave.truth() - base)));
  }
};

TYPED_TEST_SUITE_P(QuadProperties);

TYPED_TEST_P(QuadProperties, ResetAdoptsThePinLevels) {
  typename TestFixture::Bench b(1);
  b.run(2);
  EXPECT_EQ(b.out.pos, 0);
  EXPECT_EQ(b.out.vel, 0);
  EXPECT_EQ(b.out.age, TestFixture::kAgeMax);  // no edge seen yet
  EXPECT_FALSE(b.out.err || b.out.idx_armed || b.out.idx_seen);
  // All three pins go high during reset: leaving reset counts nothing.
  b.in.filt_len = 3;
  const double t = b.next_time();
  for (int c = 0; c < 3; ++c) b.wave.toggle(c, t);
  b.in.rst = true;
  b.drain();
  b.in.rst = false;
  b.run(20);
  EXPECT_EQ(b.out.pos, 0);
  EXPECT_FALSE(b.out.err);
  EXPECT_TRUE(b.out.a && b.out.b && b.out.z);
  // The same change outside reset is A and B moving together: an error,
  // not counted.
  const double t2 = b.next_time();
  b.wave.toggle(0, t2);
  b.wave.toggle(1, t2);
  b.drain();
  EXPECT_EQ(b.out.pos, 0);
  EXPECT_TRUE(b.out.err);
  EXPECT_EQ(b.out.err_cnt, 1u);
  EXPECT_FALSE(b.out.a || b.out.b);
  EXPECT_EQ(b.sim.mismatches(), 0);
}

TYPED_TEST_P(QuadProperties, LatencyLevelsThenCount) {
  typename TestFixture::Bench b(2);
  for (uint32_t len : {0u, 1u, 2u, 5u, 16u}) {
    b.in.filt_len = len;
    b.run(20);
    const int32_t before = b.out.pos;
    const double t = b.next_time(0.5);
    b.wave.edge(t, +1);
    b.wave.toggle(2, t);
    const uint64_t levels = TestFixture::level_clock_of(b, t);
    while (b.out.z != b.wave.level(2) && b.now < levels + 40) b.clock();
    EXPECT_EQ(b.now - 1, levels) << "filt_len " << len;  // b.now - 1: the clock just run
    EXPECT_EQ(b.out.a, b.wave.level(0)) << "filt_len " << len;
    EXPECT_EQ(b.out.b, b.wave.level(1)) << "filt_len " << len;
    EXPECT_EQ(b.out.pos, before) << "filt_len " << len;  // the count follows a clock later
    b.clock();
    EXPECT_EQ(b.now - 1, TestFixture::clock_of(b, t));
    EXPECT_EQ(b.out.pos, int32_t(uint32_t(before) + 1)) << "filt_len " << len;
  }
  EXPECT_EQ(b.sim.mismatches(), 0);
}

// Noise pulses shorter than filt_len - 1 clocks can cover at most filt_len - 1
// samples, whatever their phase: none may pass. They are kept apart from the
// other channel's edges (a pulse across one is flagged by design).
TYPED_TEST_P(QuadProperties, NoiseShorterThanTheFilterCountsNothing) {
  typename TestFixture::Bench b(3);
  const double ap = b.wave.aperture();
  for (uint32_t len : {2u, 3u, 4u, 8u, 16u}) {
    b.in.filt_len = len;
    b.in.idx_arm = true;  // Z noise must not trigger the index either
    b.run(len + 8);
    const double wmax = len - 1 - 2 * ap;
    for (int round = 0; round < 3; ++round) {
      const int32_t base = b.out.pos;
      const int64_t tbase = b.wave.truth();
      // Standing still: pulses on A, B, Z, never overlapping across channels.
      double t = b.next_time();
      for (int i = 0; i < 150; ++i) {
        const double w = this->uni(0.05, wmax);
        b.wave.pulse(this->pick(0, 2), t, w);
        t += w + this->uni(1 + 2 * ap + 0.05, 4);
      }
      b.drain();
      EXPECT_EQ(TestFixture::moved(b, base), 0) << "filt_len " << len;
      // Moving back and forth, a pulse between edges, clear of both.
      t = b.next_time();
      for (int i = 0; i < 50; ++i) {
        b.wave.edge(t, this->pick(0, 1) ? 1 : -1);
        if (this->pick(0, 9) < 7) b.wave.pulse(this->pick(0, 2), t + len + 2, this->uni(0.05, wmax));
        t += this->uni(2.0 * len + 4, 3.0 * len + 8);
      }
      b.drain();
      EXPECT_EQ(TestFixture::moved(b, base), TestFixture::truth_since(b, tbase)) << "filt_len " << len;
      EXPECT_FALSE(b.out.err) << "filt_len " << len;
      EXPECT_FALSE(b.out.idx_seen) << "filt_len " << len;
      EXPECT_TRUE(b.out.idx_armed);
      EXPECT_EQ(b.out.a, b.wave.level(0));
      EXPECT_EQ(b.out.b, b.wave.level(1));
    }
  }
  EXPECT_EQ(b.sim.mismatches(), 0);
}

// From each of the four phases, both ways, with and without direction
// inversion: every edge of a back-and-forth pattern counts exactly, checked
// after each edge and once more at full legal speed.
TYPED_TEST_P(QuadProperties, ReversalsAtEveryPhaseCountExactly) {
  typename TestFixture::Bench b(4);
  const int pattern[] = {1, -1, -1, 1, 1, 1, -1, -1, -1, 1};
  for (uint32_t len : {0u, 2u, 5u}) {
    for (bool inv : {false, true}) {
      b.in.filt_len = len;
      b.in.dir_inv = inv;
      const double T = std::max<double>(len, 1) + 2 * b.wave.aperture() + 0.05;  // one level per edge
      for (int phase = 0; phase < 4; ++phase) {
        for (int d : {1, -1}) {
          while (((b.wave.truth() % 4) + 4) % 4 != phase) b.move(1, 1, T);
          b.drain();
          const int32_t base = b.out.pos;
          const int64_t tbase = b.wave.truth();
          const int sign = inv ? -1 : 1;
          for (int s : pattern) {
            b.move(1, s * d, T);
            b.drain();
            ASSERT_EQ(TestFixture::moved(b, base), sign * TestFixture::truth_since(b, tbase))
                << "filt_len " << len << " inv " << inv << " phase " << phase;
          }
          double t0 = b.next_time();
          for (int s : pattern) t0 = b.move_at(1, s * d, T, t0);
          b.drain();
          EXPECT_EQ(TestFixture::moved(b, base), sign * TestFixture::truth_since(b, tbase));
          EXPECT_FALSE(b.out.err);
        }
      }
    }
  }
  EXPECT_EQ(b.sim.mismatches(), 0);
}

// Ideal quadrature at random phase to the clock. Just inside the limit of
// each filter length every edge counts and no error rises; past it the error
// flag rises; and at any rate below two edges per clock the count is exact
// or flagged, never silently wrong. (At two edges per clock A and B can
// alias to both toggling together in every sample, which a filter of 2 or
// more takes for common-mode noise.)
TYPED_TEST_P(QuadProperties, ExactUpToTheRateLimitFlaggedPastIt) {
  typename TestFixture::Bench b(5);
  for (uint32_t len : {0u, 1u, 2u, 3u, 4u, 8u}) {
    b.in.filt_len = len;
    const double lim = spacing_limit(int(len), 0, b.wave.aperture());
    for (int trial = 0; trial < 15; ++trial) {
      const int kind = trial % 3;  // inside, past, anywhere
      const double T = kind == 0   ? lim * this->uni(1.005, 1.5)
                       : kind == 1 ? lim * this->uni(0.55, 0.9)
                                   : std::max(0.55, lim * this->uni(0.3, 2.0));
      const RateTrial r = rate_trial(b, T, 0, 300, 100, this->rng);
      if (kind == 0) {
        EXPECT_TRUE(r.exact && !r.err) << "filt_len " << len << " spacing " << T;
      }
      if (kind == 1) {
        EXPECT_TRUE(r.err) << "filt_len " << len << " spacing " << T;
      }
      EXPECT_TRUE(r.exact || r.err) << "silent loss: filt_len " << len << " spacing " << T;
    }
  }
  EXPECT_EQ(b.sim.mismatches(), 0);
}

TYPED_TEST_P(QuadProperties, IndexLatchAndClear) {
  typename TestFixture::Bench b(7);
  b.in.filt_len = 2;
  const double T = 4.0;
  auto z_pulse = [&](double t) {
    b.wave.pulse(2, t, T);
    b.drain();
  };
  // Not armed: nothing.
  b.move(5, 1, T);
  z_pulse(b.next_time(T / 2));
  EXPECT_FALSE(b.out.idx_seen);
  EXPECT_EQ(b.out.idx_pos, 0);
  EXPECT_EQ(b.out.pos, 5);

  // Armed, latch only, moving either way.
  for (int dir : {1, -1}) {
    b.in.idx_arm = true;
    b.clock();
    EXPECT_TRUE(b.out.idx_armed);
    b.move(7, dir, T);
    const int32_t at = b.truth32();
    z_pulse(b.next_time(T / 2));
    EXPECT_TRUE(b.out.idx_seen);
    EXPECT_FALSE(b.out.idx_armed);
    EXPECT_EQ(b.out.idx_pos, at);
    b.move(3, dir, T);
    z_pulse(b.next_time(T / 2));  // not re-armed: no new latch
    b.drain();
    EXPECT_EQ(b.out.idx_pos, at);
    EXPECT_EQ(b.out.pos, b.truth32());
  }

  // Arming clears idx_seen; clear-on-index zeroes the position at the edge.
  b.in.idx_clr_en = true;
  b.in.idx_arm = true;
  b.clock();
  EXPECT_FALSE(b.out.idx_seen);
  b.move(5, 1, T);
  int32_t at = b.out.pos + 5;
  z_pulse(b.next_time(T / 2));
  EXPECT_EQ(b.out.idx_pos, at);
  EXPECT_EQ(b.out.pos, 0);
  b.move(2, -1, T);
  b.drain();
  EXPECT_EQ(b.out.pos, -2);

  // A falling Z edge does not trigger; the next rising one does.
  b.wave.toggle(2, b.next_time());
  b.drain();
  b.in.idx_arm = true;
  b.clock();
  b.wave.toggle(2, b.next_time());
  b.drain();
  EXPECT_TRUE(b.out.idx_armed);
  EXPECT_EQ(b.out.pos, -2);
  b.move(1, 1, T);
  z_pulse(b.next_time(T / 2));
  EXPECT_TRUE(b.out.idx_seen);
  EXPECT_EQ(b.out.idx_pos, -1);
  EXPECT_EQ(b.out.pos, 0);

  // Disarm cancels.
  b.move(4, 1, T);
  b.in.idx_arm = true;
  b.clock();
  b.in.idx_disarm = true;
  b.clock();
  EXPECT_FALSE(b.out.idx_armed);
  z_pulse(b.next_time(T / 2));
  EXPECT_FALSE(b.out.idx_seen);
  EXPECT_EQ(b.out.pos, 4);

  // Arming in the clock of the filtered Z rise is too late for that edge;
  // one clock earlier is in time.
  for (int early = 0; early < 2; ++early) {
    const double t = b.next_time(T / 2);
    b.wave.pulse(2, t, T);
    TestFixture::run_to(b, TestFixture::clock_of(b, t) - uint64_t(early));
    b.in.idx_arm = true;
    b.drain();
    EXPECT_EQ(b.out.idx_seen, early == 1) << "early " << early;
    EXPECT_EQ(b.out.idx_armed, early == 0) << "early " << early;
    if (early == 0) {
      b.in.idx_disarm = true;
      b.clock();
    }
  }
  EXPECT_EQ(b.out.pos, 0);

  // A count edge in the very clock of the index edge: the latched position
  // includes it, and it is that position that becomes 0.
  b.move(3, 1, T);
  b.in.idx_arm = true;
  b.drain();
  const double t = b.next_time();
  b.wave.edge(t, 1);
  b.wave.pulse(2, t, T);
  b.drain();
  EXPECT_EQ(b.out.idx_pos, 4);
  EXPECT_EQ(b.out.pos, 0);

  // A load in the clock of the index edge wins over the clear.
  b.in.idx_arm = true;
  b.drain();
  const double t2 = b.next_time();
  b.wave.pulse(2, t2, T);
  TestFixture::run_to(b, TestFixture::clock_of(b, t2));
  b.in.pos_load = true;
  b.in.pos_load_val = 1234;
  b.drain();
  EXPECT_TRUE(b.out.idx_seen);
  EXPECT_EQ(b.out.idx_pos, 0);
  EXPECT_EQ(b.out.pos, 1234);
  EXPECT_EQ(b.sim.mismatches(), 0);
}

TYPED_TEST_P(QuadProperties, LoadStrobeAndWrap) {
  typename TestFixture::Bench b(8);
  const double T = 3.0;
  b.in.pos_load = true;
  b.in.pos_load_val = -77;
  b.clock();
  EXPECT_EQ(b.out.pos, -77);
  b.move(10, 1, T);
  b.drain();
  EXPECT_EQ(b.out.pos, -67);
  // The position wraps like any 32-bit counter.
  b.in.pos_load = true;
  b.in.pos_load_val = INT32_MAX;
  b.clock();
  b.move(1, 1, T);
  b.drain();
  EXPECT_EQ(b.out.pos, INT32_MIN);
  b.move(1, -1, T);
  b.drain();
  EXPECT_EQ(b.out.pos, INT32_MAX);
  // A load in the clock of a count: pos_o takes the loaded value, the
  // velocity still sees the edge.
  b.in.sample = true;
  b.clock();
  const double t = b.next_time();
  b.wave.edge(t, 1);
  TestFixture::run_to(b, TestFixture::clock_of(b, t));
  b.in.pos_load = true;
  b.in.pos_load_val = 5;
  b.clock();
  EXPECT_EQ(b.out.pos, 5);
  b.in.sample = true;
  b.clock();
  EXPECT_EQ(b.out.vel, 1);
  EXPECT_EQ(b.sim.mismatches(), 0);
}

TYPED_TEST_P(QuadProperties, ErrorFlagClearAndSaturation) {
  typename TestFixture::Bench b(9);
  // A and B together, kErrMax + 3 times: the counter saturates, the count
  // does not move.
  double t = b.next_time();
  const uint32_t n = TestFixture::kErrMax + 3;
  for (uint32_t i = 0; i < n; ++i, t += 2) {
    b.wave.toggle(0, t);
    b.wave.toggle(1, t);
  }
  b.drain();
  EXPECT_TRUE(b.out.err);
  EXPECT_EQ(b.out.err_cnt, TestFixture::kErrMax);
  EXPECT_EQ(b.out.pos, 0);
  b.in.err_clr = true;
  b.clock();
  EXPECT_FALSE(b.out.err);
  EXPECT_EQ(b.out.err_cnt, 0u);
  // An error in the clock of the clear survives it.
  t = b.next_time();
  b.wave.toggle(0, t);
  b.wave.toggle(1, t);
  TestFixture::run_to(b, TestFixture::clock_of(b, t));
  b.in.err_clr = true;
  b.clock();
  EXPECT_TRUE(b.out.err);
  EXPECT_EQ(b.out.err_cnt, 1u);
  EXPECT_EQ(b.sim.mismatches(), 0);
}

// vel_o at each strobe equals the sum of the count steps seen in pos_o since
// the previous strobe (held at the VEL_W extremes), and age_o the clocks
// pos_o had held its value, whatever the sample period, direction and speed.
TYPED_TEST_P(QuadProperties, VelocityIsTheCountDifferencePerSample) {
  typename TestFixture::Bench b(10);
  int64_t acc = 0;
  uint32_t held = TestFixture::kAgeMax;
  int samples = 0;
  auto clock = [&] {
    const int64_t expect_vel = acc;
    const uint32_t expect_age = held;
    const bool sample = b.in.sample;
    const int32_t before = b.out.pos;
    b.clock();
    const int32_t d = TestFixture::moved(b, before);
    ASSERT_LE(std::abs(d), 1);
    if (sample) {
      ASSERT_EQ(b.out.vel, expect_vel) << "sample " << samples;
      ASSERT_EQ(b.out.age, expect_age) << "sample " << samples;
      ++samples;
      acc = 0;
    }
    if (acc + d <= TestFixture::kVelMax && acc + d >= TestFixture::kVelMin) acc += d;
    held = d != 0 ? 0 : std::min(held + 1, TestFixture::kAgeMax);
  };
  for (int episode = 0; episode < 40; ++episode) {
    b.in.filt_len = uint32_t(this->pick(0, 4));
    b.in.dir_inv = this->pick(0, 1) == 1;
    const double lim = 2 * spacing_limit(int(b.in.filt_len), 0, b.wave.aperture());
    const int dir = this->pick(0, 1) ? 1 : -1;
    double t = b.next_time();
    for (int i = 0; i < 200; ++i, t += this->uni(lim, lim * 8))
      b.wave.edge(t, this->pick(0, 9) < 8 ? dir : -dir);
    const int period = this->pick(1, 300);
    while (double(b.now) < t + 10 && !this->HasFailure()) {
      b.in.sample = b.now % uint64_t(period) == 0;
      clock();
    }
  }
  // A long stop: the age saturates.
  for (uint32_t i = 0; i < TestFixture::kAgeMax + 10; ++i) clock();
  b.in.sample = true;
  clock();
  EXPECT_EQ(b.out.age, TestFixture::kAgeMax);
  EXPECT_GT(samples, 100);
  EXPECT_EQ(b.sim.mismatches(), 0);
}

// The latch strobe (a home switch, the probe) latches as an index edge
// does: only when armed, the position of its own clock (a count edge in
// that clock included), once.
TYPED_TEST_P(QuadProperties, LatchStrobeLatchesLikeAnIndexEdge) {
  typename TestFixture::Bench b(11);
  b.in.filt_len = 2;
  const double T = 4.0;
  b.move(6, 1, T);
  b.drain();
  b.in.latch = true;  // not armed: nothing
  b.clock();
  b.drain();
  EXPECT_FALSE(b.out.idx_seen);
  for (int dir : {1, -1}) {
    b.in.idx_arm = true;
    b.clock();
    b.move(3, dir, T);
    b.drain();
    const int32_t at = b.out.pos;
    b.in.latch = true;
    b.clock();
    EXPECT_TRUE(b.out.idx_seen);
    EXPECT_FALSE(b.out.idx_armed);
    b.drain();
    EXPECT_EQ(b.out.idx_pos, at);
    b.move(2, dir, T);  // disarmed by the first: a strobe elsewhere changes nothing
    b.drain();
    b.in.latch = true;
    b.clock();
    b.drain();
    EXPECT_NE(b.out.pos, at);
    EXPECT_EQ(b.out.idx_pos, at);
  }
  // A count edge in the strobe's clock: the latched position includes it.
  b.in.idx_arm = true;
  b.clock();
  const double t = b.next_time();
  b.wave.edge(t, 1);
  TestFixture::run_to(b, TestFixture::clock_of(b, t));
  const int32_t before = b.out.pos;
  b.in.latch = true;  // the next clock is the one that counts the edge
  b.clock();
  EXPECT_EQ(b.out.pos, before + 1);
  b.drain();
  EXPECT_TRUE(b.out.idx_seen);
  EXPECT_EQ(b.out.idx_pos, before + 1);
  EXPECT_EQ(b.out.pos, b.truth32());
  EXPECT_EQ(b.sim.mismatches(), 0);
}

REGISTER_TYPED_TEST_SUITE_P(QuadProperties, ResetAdoptsThePinLevels, LatencyLevelsThenCount,
                            NoiseShorterThanTheFilterCountsNothing, ReversalsAtEveryPhaseCountExactly,
                            ExactUpToTheRateLimitFlaggedPastIt, IndexLatchAndClear,
                            LatchStrobeLatchesLikeAnIndexEdge, LoadStrobeAndWrap, ErrorFlagClearAndSaturation,
                            VelocityIsTheCountDifferencePerSample);

}  // namespace mc::test
