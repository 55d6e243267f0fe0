// pid_core C/RTL co-simulation: random and directed stimulus, every sample
// compared bit for bit against the hls/ twin, plus the behaviour the directed
// cases are about (checked on the RTL's outputs, not only their agreement).
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "Vpid_core.h"
#include "Vpid_core1.h"
#include "Vpid_core1___024root.h"
#include "Vpid_core___024root.h"
#include "Vpid_core_noloops.h"
#include "Vpid_core_noloops___024root.h"
#include "pid_harness.hpp"

namespace mc::test {
namespace {

// The default build (three axes) carries every test; a one-axis build checks
// that the parameter, the one-bit axis field and the 16-word RAM hold up.
using PidCosim = PidCosimT<Vpid_core, 3>;
using PidCosim1 = PidCosimT<Vpid_core1, 1>;
// The stepper board's build: the datapath without its loops.
using PidCosimNoLoops = PidCosimT<Vpid_core_noloops, 3, false>;
constexpr int kAxes = PidCosim::kAxes;

using namespace mc::pid_reg;

uint64_t env_count(const char* name, uint64_t dflt) {
  const char* v = std::getenv(name);
  return v ? std::strtoull(v, nullptr, 10) : dflt;
}

uint32_t coef(int32_t m, int s) {
  return coef_pack(Coef{m, s});
}

// Random stimulus in episodes. Each episode draws a configuration style:
// "physical" (gains that keep the output mostly inside its range, feedback
// near the command) or "wild" (any bit pattern in any register, any inputs),
// then perturbs registers, enables and Ts while samples run.
class Stim {
 public:
  explicit Stim(uint64_t seed) : rng_(seed) {}

  uint32_t u32() { return uint32_t(rng_()); }
  int32_t i32() { return int32_t(u32()); }
  int range(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }

  // Integer with a random magnitude scale, so small and huge values both occur.
  int32_t scaled() {
    const int bits = range(0, 32);
    if (bits == 32) return chance(0.5) ? INT32_MAX : INT32_MIN;
    const int64_t v = int64_t(u32() & ((uint64_t(1) << bits) - 1));
    return int32_t(chance(0.5) ? -v : v);
  }

  uint32_t coef_word(bool wild) {
    if (wild) return chance(0.2) ? u32() : coef(int32_t(sext(u32(), COEF_M_W)), range(0, 63));
    // Normalized mantissa, shift over the range gains actually use.
    const int32_t m = range(1 << 22, (1 << 23) - 1) * (chance(0.1) ? -1 : 1);
    return coef(m, range(18, 63));
  }

  uint32_t reg_value(uint8_t r, bool wild) {
    switch (r) {
      case ILIM:
      case OLIM:
        return chance(0.2) ? 0 : (wild ? u32() : uint32_t(range(1, 32767)));
      case DBAND:
        return chance(0.5) ? 0 : (wild ? u32() : uint32_t(range(0, 20)));
      case ELIM:
        return chance(0.5) ? 0 : (wild ? u32() : uint32_t(range(1, 1 << 20)));
      default:
        return coef_word(wild);
    }
  }

  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
};

template <typename Sim>
void configure_axis(Sim& sim, Stim& st, int a, bool wild) {
  for (uint8_t r = 0; r < NREGS_RAM; ++r) sim.write(addr(uint8_t(a), r), st.reg_value(r, wild));
  sim.write(addr(uint8_t(a), CTRL), st.chance(0.9) ? 1u : 0u);
}

template <typename Sim>
void random_bit_exact(uint64_t n) {
  constexpr int kN = Sim::kAxes;
  const uint64_t seed = env_count("MC_SEED", 20261121);
  Sim sim{uint32_t(seed)};
  Stim st(seed);
  std::array<int32_t, kN> cmd{}, fb{};
  bool wild = false;
  uint64_t next_episode = 0;
  while (sim.samples() < n) {
    if (sim.samples() >= next_episode) {
      wild = st.chance(0.3);
      for (int a = 0; a < kN; ++a) configure_axis(sim, st, a, wild);
      // Mostly the shortest Ts (fast), sometimes longer, sometimes below the
      // minimum to exercise the clamp.
      const int tsel = st.range(0, 9);
      const uint32_t ts = tsel < 7 ? uint32_t(sim.Vlat()) : (tsel < 9 ? uint32_t(st.range(1, 200)) : 0u);
      sim.write(addr(GLOBAL_AXIS, G_TS), ts);
      next_episode = sim.samples() + uint64_t(st.range(50, 3000));
      for (int a = 0; a < kN; ++a) {
        cmd[a] = st.scaled();
        fb[a] = wild ? st.scaled() : sat32(i128(cmd[a]) + st.range(-300, 300));
      }
    }
    // Inputs move every sample: a trajectory plus noise in physical episodes.
    for (int a = 0; a < kN; ++a) {
      if (wild) {
        cmd[a] = st.chance(0.3) ? st.scaled() : cmd[a];
        fb[a] = st.chance(0.3) ? st.scaled() : fb[a];
      } else {
        const int32_t step = st.range(-50, 50);
        cmd[a] = sat32(i128(cmd[a]) + step);
        fb[a] = sat32(i128(fb[a]) + (cmd[a] > fb[a] ? 1 : -1) * st.range(0, 60) + st.range(-2, 2));
      }
    }
    sim.set_inputs(cmd, fb);
    // Occasional register writes and enable toggles between samples.
    if (st.chance(0.02)) {
      const uint8_t a = uint8_t(st.range(0, kN - 1));
      const uint8_t r = uint8_t(st.range(0, NREGS_RAM - 1));
      sim.write(addr(a, r), st.reg_value(r, wild));
    }
    if (st.chance(0.005)) sim.write(addr(uint8_t(st.range(0, kN - 1)), CTRL), st.u32() & 1);
    if (st.chance(0.0005)) sim.read(addr(uint8_t(st.range(0, 15)), uint8_t(st.range(0, 15))));
    ASSERT_TRUE(sim.run_sample()) << "no sweep completed";
    ASSERT_EQ(sim.mismatches(), 0) << "seed " << seed;
  }
  EXPECT_EQ(sim.mismatches(), 0);
  ::testing::Test::RecordProperty("samples", std::to_string(sim.samples()));
}

TEST(PidRtl, RandomBitExact) {
  random_bit_exact<PidCosim>(env_count("MC_PID_RTL_SAMPLES", 1000000));
}

TEST(PidRtl, RandomBitExactOneAxis) {
  random_bit_exact<PidCosim1>(env_count("MC_PID_RTL_SAMPLES", 1000000) / 4);
}

TEST(PidRtl, RandomBitExactWithoutLoops) {
  random_bit_exact<PidCosimNoLoops>(env_count("MC_PID_RTL_SAMPLES", 1000000) / 4);
}

// SERVO = 0: an enable is refused, the drive output stays 0 whatever the
// gains and the error, and the front end (error, deadband) still works,
// for the sample stream the board's telemetry reads.
TEST(PidRtl, WithoutLoopsNoAxisCanBeEnabled) {
  PidCosimNoLoops sim(3);
  for (int a = 0; a < kAxes; ++a) {
    sim.write(addr(uint8_t(a), KP), coef(3 << 20, 20));
    sim.write(addr(uint8_t(a), KI), coef(1 << 20, 20));
    sim.write(addr(uint8_t(a), OLIM), 30000);
    sim.write(addr(uint8_t(a), CTRL), 1);
    EXPECT_EQ(sim.read(addr(uint8_t(a), CTRL)), 0u) << "axis " << a;
    EXPECT_EQ(sim.read(addr(uint8_t(a), OLIM)), 30000u) << "the gains still read back";
  }
  for (int i = 0; i < 20; ++i) {
    sim.set_inputs({1000 + i, -500, 7}, {0, 0, 0});
    ASSERT_TRUE(sim.run_sample());
    for (int a = 0; a < kAxes; ++a) {
      EXPECT_EQ(sim.u(a), 0) << "axis " << a;
      EXPECT_FALSE(sim.sat(a)) << "axis " << a;
    }
    EXPECT_EQ(sim.err(0), 1000 + i);
    EXPECT_EQ(sim.err(1), -500);
  }
  EXPECT_EQ(sim.mismatches(), 0);
}

TEST(PidRtl, LatencyPeriodAndTsClamp) {
  PidCosim sim(1);
  const int lat = PidCosim::Vlat();
  EXPECT_EQ(sim.read(addr(GLOBAL_AXIS, G_LATENCY)), uint32_t(lat));
  EXPECT_EQ(sim.read(addr(GLOBAL_AXIS, G_NAXES)), uint32_t(kAxes));
  for (uint32_t ts : {uint32_t(lat), uint32_t(lat + 1), 100u, 1000u}) {
    sim.write(addr(GLOBAL_AXIS, G_TS), ts);
    EXPECT_EQ(sim.read(addr(GLOBAL_AXIS, G_TS)), ts);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(sim.run_sample());
    EXPECT_EQ(sim.last_period(), ts);
    EXPECT_EQ(sim.last_latency(), uint64_t(lat));
  }
  // Below the sweep time the period clamps to the latency; nothing is lost.
  sim.write(addr(GLOBAL_AXIS, G_TS), 3);
  EXPECT_EQ(sim.read(addr(GLOBAL_AXIS, G_TS)), uint32_t(lat));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(sim.run_sample());
  EXPECT_EQ(sim.last_period(), uint64_t(lat));
}

TEST(PidRtl, RegisterReadBack) {
  PidCosim sim(2);
  Stim st(2);
  for (int a = 0; a < kAxes; ++a)
    for (uint8_t r = 0; r < NREGS_RAM; ++r) {
      const uint32_t v = st.u32();
      sim.write(addr(uint8_t(a), r), v);
      EXPECT_EQ(sim.read(addr(uint8_t(a), r)), v);
    }
  sim.write(addr(1, CTRL), 0xFFFFFFFFu);
  EXPECT_EQ(sim.read(addr(1, CTRL)), 1u);
  // Unmapped registers and axes read as zero.
  EXPECT_EQ(sim.read(addr(0, 0xC)), 0u);
  EXPECT_EQ(sim.read(addr(kAxes, KP)), 0u);
  EXPECT_EQ(sim.read(addr(GLOBAL_AXIS, 0x7)), 0u);
}

// Fixture for directed cases: axis 0 active, all others disabled.
class PidDirected : public ::testing::Test {
 protected:
  PidDirected() : sim(7) {}
  void set(uint8_t r, uint32_t v) { sim.write(addr(0, r), v); }
  void enable(bool on) { sim.write(addr(0, CTRL), on ? 1u : 0u); }
  void step(int32_t cmd, int32_t fb) {
    sim.set_inputs({cmd, 0, 0}, {fb, 0, 0});
    ASSERT_TRUE(sim.run_sample());
  }
  PidCosim sim;
};

TEST_F(PidDirected, ProportionalAndSaturationBothWays) {
  set(KP, coef(3 << 20, 20));  // kp = 3
  set(OLIM, 1000);
  enable(true);
  step(0, 0);
  step(0, 0);
  step(100, 0);
  EXPECT_EQ(sim.u(0), 300);
  EXPECT_FALSE(sim.sat(0));
  step(1000, 0);
  EXPECT_EQ(sim.u(0), 1000);
  EXPECT_TRUE(sim.sat(0));
  step(-1000, 0);
  EXPECT_EQ(sim.u(0), -1000);
  EXPECT_TRUE(sim.sat(0));
  // Extreme inputs: the difference saturates, never wraps.
  step(INT32_MIN, INT32_MAX);
  EXPECT_EQ(sim.err(0), INT32_MIN);
  EXPECT_EQ(sim.u(0), -1000);
  step(INT32_MAX, INT32_MIN);
  EXPECT_EQ(sim.err(0), INT32_MAX);
  EXPECT_EQ(sim.u(0), 1000);
  // Output limit 0 means full scale.
  set(OLIM, 0);
  step(20000, 0);
  EXPECT_EQ(sim.u(0), OUT_MAX);
  step(-20000, 0);
  EXPECT_EQ(sim.u(0), -OUT_MAX);
}

TEST_F(PidDirected, DeadbandEdges) {
  set(KP, coef(1 << 22, 22));  // kp = 1
  set(DBAND, 5);
  enable(true);
  for (int32_t e = -12; e <= 12; ++e) {
    step(e, 0);
    const int32_t expect = e > 5 ? e - 5 : (e < -5 ? e + 5 : 0);
    EXPECT_EQ(sim.err(0), expect) << "e=" << e;
    EXPECT_EQ(sim.u(0), expect) << "e=" << e;
  }
}

TEST_F(PidDirected, ErrorClamp) {
  set(KP, coef(1 << 22, 22));
  set(ELIM, 50);
  enable(true);
  step(49, 0);
  EXPECT_EQ(sim.u(0), 49);
  step(51, 0);
  EXPECT_EQ(sim.u(0), 50);
  step(-100000, 0);
  EXPECT_EQ(sim.u(0), -50);
}

TEST_F(PidDirected, AntiWindupLeavesSaturationOnSignChange) {
  set(KP, coef(1 << 22, 22));      // kp = 1
  set(KI, coef(1 << 22, 22 + 6));  // ki = 1/64 per sample
  set(OLIM, 2000);
  enable(true);
  for (int i = 0; i < 5000; ++i) step(10000, 0);  // long saturation
  EXPECT_EQ(sim.u(0), 2000);
  EXPECT_TRUE(sim.sat(0));
  step(-1, 0);  // the error changes sign
  EXPECT_FALSE(sim.sat(0));
  EXPECT_LT(sim.u(0), 2000);
  // And the other way.
  for (int i = 0; i < 5000; ++i) step(-10000, 0);
  EXPECT_EQ(sim.u(0), -2000);
  step(1, 0);
  EXPECT_FALSE(sim.sat(0));
  EXPECT_GT(sim.u(0), -2000);
}

TEST_F(PidDirected, IntegratorLimit) {
  set(KI, coef(1 << 22, 22 + 4));  // ki = 1/16
  set(ILIM, 300);
  enable(true);
  for (int i = 0; i < 2000; ++i) step(10, 0);
  EXPECT_EQ(sim.u(0), 300);
  EXPECT_FALSE(sim.sat(0));
  for (int i = 0; i < 2000; ++i) step(-10, 0);
  EXPECT_EQ(sim.u(0), -300);
}

TEST_F(PidDirected, EnableClearsStateAndIsBumpless) {
  set(KP, coef(1 << 22, 22));
  set(KI, coef(1 << 22, 22 + 2));
  set(KD_A, coef(int32_t(0.5 * (1 << 23)), 23 + D_OPER_FRAC));
  set(KD_B, coef(1 << 22, 22 + 1));
  enable(true);
  for (int i = 0; i < 100; ++i) step(100, 0);
  EXPECT_NE(sim.twin().state(0).i, 0);
  enable(false);
  step(100, 0);
  EXPECT_EQ(sim.u(0), 0);
  EXPECT_EQ(sim.twin().state(0).i, 0);
  EXPECT_EQ(sim.twin().state(0).d, 0);
  // The command keeps moving while disabled; at enable the loop sees only the
  // present error (no derivative kick from stale history, no old integral).
  for (int i = 0; i < 10; ++i) step(100 + i * 7, 100 + i * 7);
  enable(true);
  step(163, 163);
  EXPECT_EQ(sim.u(0), 0);
}

TEST_F(PidDirected, LargestAndSmallestCoefficients) {
  // The largest coefficient magnitude: mantissa -2^23, shift 0 (-8.4e6/count):
  // saturates for any nonzero error, in both directions.
  set(KP, coef(-(1 << 23), 0));
  enable(true);
  step(1, 0);
  EXPECT_EQ(sim.u(0), -OUT_MAX);
  step(-1, 0);
  EXPECT_EQ(sim.u(0), OUT_MAX);
  // The smallest: mantissa 1, shift 63 (1.1e-19/count). Its products are far
  // below one output unit, but the integrator keeps them: 2^31 * 2^-63 * 2^32
  // = 1 accumulator LSB per sample.
  set(KP, 0);
  set(KI, coef(1, 63));
  step(INT32_MAX, 0);
  step(INT32_MAX, 0);
  EXPECT_EQ(sim.u(0), 0);
  EXPECT_GT(sim.twin().state(0).i, 0);
  // Mantissa at its positive extreme and the largest useful shift.
  set(KI, 0);
  set(KP, coef((1 << 23) - 1, 63));
  step(INT32_MAX, 0);
  EXPECT_EQ(sim.u(0), 0);
}

TEST_F(PidDirected, VelocityFeedForward) {
  set(KF1, coef(1 << 22, 22 + 1));  // 0.5 per count/sample
  enable(true);
  for (int k = 0; k < 20; ++k) step(10 * k, 10 * k);
  EXPECT_EQ(sim.u(0), 5);
}

}  // namespace
}  // namespace mc::test
