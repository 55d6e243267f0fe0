// The host-loop event model: without jitter and latency it is PidDouble at
// k * period; outputs take effect exactly io_latency after their wake; wakes
// strictly increase and late ones are overruns; deterministic per seed.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "host/base/errors.hpp"
#include "host/control/pid_double.hpp"
#include "sim/plant/host_loop.hpp"

namespace mc::sim {
namespace {

const mc::host::PidGains kGains{2, 30, 0.05, 5e-3, 0.01};

double cmd_at(double t) {
  return 1000 * std::sin(2 * M_PI * 0.7 * t) + (t > 0.3 ? 500 : 0);
}
double fb_at(double t) {
  return 900 * std::sin(2 * M_PI * 0.7 * t - 0.2);
}

TEST(HostLoop, NoJitterNoLatencyIsThePidAtEveryPeriod) {
  HostLoopConfig cfg{kGains, 0.01, 0.0};
  HostLoop loop(cfg, JitterSampler(zero_jitter(0.01), 1));
  mc::host::PidDouble ref(kGains);
  for (int k = 0; k < 300; ++k) {
    const double t = loop.next_wake_s();
    ASSERT_DOUBLE_EQ(t, k * 0.01);
    loop.wake(cmd_at(t), fb_at(t));
    const double u = ref.update(cmd_at(t), fb_at(t));
    EXPECT_EQ(loop.output_at(t), u) << k;
    EXPECT_EQ(loop.output_at(t + 0.005), u) << k;  // held until the next
  }
  EXPECT_EQ(loop.wakes(), 300u);
  EXPECT_EQ(loop.overruns(), 0u);
}

TEST(HostLoop, OutputsTakeEffectExactlyIoLatencyAfterTheWake) {
  HostLoopConfig cfg{kGains, 0.01, 0.001};
  HostLoop loop(cfg, JitterSampler(default_jitter(), 3));
  EXPECT_EQ(loop.output_at(-1), 0.0);
  mc::host::PidDouble ref(kGains);
  double prev_u = 0, prev_wake = -1;
  for (int k = 0; k < 200; ++k) {
    const double t = loop.next_wake_s();
    ASSERT_GT(t, prev_wake);
    ASSERT_GE(t, k * 0.01);  // never before its deadline
    loop.wake(cmd_at(t), fb_at(t));
    const double u = ref.update(cmd_at(t), fb_at(t));  // inputs as of the wake, nominal Ts
    // Just before the apply time the previous output still holds.
    EXPECT_EQ(loop.output_at(std::nextafter(t + 0.001, 0.0)), prev_u) << k;
    EXPECT_EQ(loop.output_at(t + 0.001), u) << k;
    prev_u = u;
    prev_wake = t;
  }
}

// A histogram whose every wake is 1.5 periods late: each wake overruns and
// the loop runs back to back behind its deadlines, never going backwards.
TEST(HostLoop, LateWakesAreOverrunsAndTheLoopRunsBehind) {
  JitterHistogram h = zero_jitter(0.01);
  h.lo_s = {0.015};
  h.hi_s = {0.015};
  HostLoop loop(HostLoopConfig{kGains, 0.01, 0.0}, JitterSampler(h, 1));
  double prev = -1;
  for (int k = 0; k < 10; ++k) {
    const double t = loop.next_wake_s();
    EXPECT_NEAR(t, k * 0.01 + 0.015, 1e-12);
    EXPECT_GT(t, prev);
    prev = t;
    loop.wake(0, 0);
  }
  EXPECT_EQ(loop.overruns(), 10u);
}

TEST(HostLoop, BackToBackWhenLatenessVaries) {
  // 25 ms then 0 late alternately: the on-time deadline after a late wake is
  // already past, so that wake follows the late one immediately.
  JitterHistogram h = zero_jitter(0.01);
  h.lo_s = {0, 0.025};
  h.hi_s = {0, 0.025};
  h.count = {1, 1};
  HostLoop loop(HostLoopConfig{kGains, 0.01, 0.0}, JitterSampler(h, 9));
  double prev = -1;
  for (int k = 0; k < 2000; ++k) {
    const double t = loop.next_wake_s();
    ASSERT_GE(t, prev + HostLoop::kBackToBack_s * (1 - 1e-9)) << k;
    prev = t;
    loop.wake(0, 0);
  }
  EXPECT_GT(loop.overruns(), 500u);
  EXPECT_LT(loop.overruns(), 1500u);
}

TEST(HostLoop, DeterministicPerSeed) {
  const auto trace = [](uint64_t seed) {
    HostLoop loop(HostLoopConfig{kGains}, JitterSampler(default_jitter(), seed));
    std::vector<double> w;
    for (int k = 0; k < 500; ++k) {
      const double t = loop.next_wake_s();
      w.push_back(t);
      loop.wake(cmd_at(t), fb_at(t));
      w.push_back(loop.output_at(t + 0.001));
    }
    return w;
  };
  EXPECT_EQ(trace(11), trace(11));
  EXPECT_NE(trace(11), trace(12));
}

TEST(HostLoop, RejectsInconsistentConfig) {
  const auto make = [](HostLoopConfig c) { HostLoop l(c, JitterSampler(zero_jitter(0.01), 1)); };
  EXPECT_THROW(make(HostLoopConfig{kGains, 0.001}), mc::host::InputError);  // gains.ts != period
  EXPECT_THROW(make(HostLoopConfig{kGains, 0.01, -1e-3}), mc::host::InputError);
  EXPECT_THROW(make(HostLoopConfig{kGains, 0.0}), mc::host::InputError);
}

}  // namespace
}  // namespace mc::sim
