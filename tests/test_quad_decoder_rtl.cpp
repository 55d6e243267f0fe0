// quad_decoder C/RTL co-simulation: the property suite run through the
// lock-step co-simulation (every output compared every clock), plus long
// random runs where any input may do anything at any clock.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "Vquad_decoder.h"
#include "Vquad_decoder_idxram.h"
#include "Vquad_decoder_small.h"
#include "quad_cosim.hpp"
#include "quad_properties.hpp"

namespace mc::test {
namespace {

using QuadCosim = QuadCosimT<Vquad_decoder, QuadDefault>;
using QuadCosimSmall = QuadCosimT<Vquad_decoder_small, QuadSmall>;
using QuadCosimIdxRam = QuadCosimT<Vquad_decoder_idxram, QuadIdxRam>;

using CosimSims = ::testing::Types<QuadCosim, QuadCosimSmall>;
INSTANTIATE_TYPED_TEST_SUITE_P(Rtl, QuadProperties, CosimSims);

// What the random runs reached, seen from the outputs.
struct Coverage {
  uint64_t counts = 0, index_hits = 0, errors = 0, vel_nonzero = 0;
  void count(const QuadOut& prev, const QuadOut& o) {
    counts += o.pos != prev.pos;
    index_hits += o.idx_seen && !prev.idx_seen;
    errors += o.err_cnt != prev.err_cnt && o.err_cnt != 0;
    vel_nonzero += o.vel != prev.vel && o.vel != 0;
  }
  void record() const {
    ::testing::Test::RecordProperty("counts", std::to_string(counts));
    ::testing::Test::RecordProperty("index_hits", std::to_string(index_hits));
    ::testing::Test::RecordProperty("errors", std::to_string(errors));
    ::testing::Test::RecordProperty("vel_nonzero", std::to_string(vel_nonzero));
  }
  void expect_all() const {
    EXPECT_GT(counts, 10000u);
    EXPECT_GT(index_hits, 100u);
    EXPECT_GT(errors, 1000u);
    EXPECT_GT(vel_nonzero, 1000u);
  }
};

// Random stimulus in episodes. Each draws a configuration, strobe rates and
// a pin source: either raw random bits (anything at all, including A and B
// together) or an encoder waveform at a random speed with noise and index
// pulses, sampled with a random metastable window.
template <typename Sim>
void random_bit_exact(uint64_t cycles, uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uni = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  auto chance = [&](double p) { return std::bernoulli_distribution(p)(rng); };
  Sim sim{uint32_t(seed)};
  QuadIn in;
  QuadOut prev;
  Coverage cover;
  uint64_t now = 0;
  while (now < cycles) {
    const uint32_t lens[] = {0, 1, 2, 3, 4, 8, 16, uint32_t(rng())};
    in.filt_len = chance(0.05) ? uint32_t(rng()) & 0xFF : lens[pick(0, 6 + int(chance(0.1)))];
    in.dir_inv = chance(0.5);
    in.idx_clr_en = chance(0.5);
    const double p_load = chance(0.5) ? 0.0005 : 0.0, p_arm = uni(0, 0.01), p_disarm = uni(0, 0.002);
    const double p_clr = uni(0, 0.002), p_rst = chance(0.2) ? 0.0002 : 0.0;
    const int period = pick(1, 400);
    const bool raw = chance(0.3);
    const double p_toggle[3] = {uni(0, 0.5), uni(0, 0.5), uni(0, 0.2)};
    EncoderWave wave(rng(), uni(0, 0.1));
    const double T = std::exp(uni(std::log(0.4), std::log(40.0)));  // clocks per edge
    const double t0 = double(now);
    double t = t0;
    int dir = 1;
    const uint64_t end = now + uint64_t(pick(1000, 40000));
    bool pins[3] = {in.a, in.b, in.z};
    if (!raw)  // the waveform starts from the pins' present levels
      for (int c = 0; c < 3; ++c)
        if (pins[c]) wave.toggle(c, t0 - 1);
    for (; now < end; ++now) {
      if (raw) {
        for (int c = 0; c < 3; ++c) pins[c] = pins[c] != chance(p_toggle[c]);
        in.a = pins[0];
        in.b = pins[1];
        in.z = pins[2];
      } else {
        while (wave.last() < double(now) + 50) {
          if (chance(0.02)) dir = -dir;
          t += T * uni(0.8, 1.2);
          wave.edge(t, dir);
          if (chance(0.1)) wave.pulse(pick(0, 2), t + uni(0, T), uni(0, 6));
          if (chance(0.01)) wave.pulse(2, t + uni(0, T), uni(0, 3 * T));
        }
        wave.sample(double(now), in);
      }
      in.rst = chance(p_rst) || (in.rst && chance(0.6));
      in.pos_load = chance(p_load);
      in.pos_load_val = int32_t(rng());
      in.idx_arm = chance(p_arm);
      in.idx_disarm = chance(p_disarm);
      in.err_clr = chance(p_clr);
      in.sample = now % uint64_t(period) == 0;
      const QuadOut o = sim.cycle(in);
      cover.count(prev, o);
      prev = o;
    }
    if (!raw) {
      in.a = wave.level(0);  // where the waveform left the pins
      in.b = wave.level(1);
      in.z = wave.level(2);
    }
    ASSERT_EQ(sim.mismatches(), 0) << "seed " << seed;
  }
  ::testing::Test::RecordProperty("cycles", std::to_string(now));
  cover.record();
  // A run of the default length must have reached every corner it is for.
  if (cycles >= 1000000) cover.expect_all();
}

TEST(QuadRtl, RandomBitExact) {
  random_bit_exact<QuadCosim>(env_count("MC_QUAD_RTL_CYCLES", 2000000), env_count("MC_SEED", 20261122));
}

TEST(QuadRtl, RandomBitExactSmallWidths) {
  random_bit_exact<QuadCosimSmall>(env_count("MC_QUAD_RTL_CYCLES", 2000000) / 4, env_count("MC_SEED", 7));
}

// The board's build: the index latch in block RAM (a clock later, kept
// through reset), and the filter lengths it has.
TEST(QuadRtl, RandomBitExactIndexInBlockRam) {
  random_bit_exact<QuadCosimIdxRam>(env_count("MC_QUAD_RTL_CYCLES", 2000000) / 2, env_count("MC_SEED", 11));
}

}  // namespace
}  // namespace mc::test
