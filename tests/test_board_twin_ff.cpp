// The running interpolator's fast-forward (InterpCore::run_quiet/skip_run,
// and MotionCore's skip while a segment runs) against clocking every clock:
// random lines, arcs and dwells at random feeds, with feed holds and clears
// now and then; the skipping twin and the clocked one must agree on the
// position command, the feed phase and the queue after every skip and every
// clock, and end together. The co-simulation and the board twin rest on it
// (Cosim.TwinAndRtlGiveIdenticalOutputs and BoardTwin.* check it further
// against the RTL).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "hls/interp_core.hpp"
#include "hls/motion_core.hpp"
#include "hls/quad_decoder.hpp"
#include "interp_bench.hpp"

namespace mc::test {
namespace {

using Interp = InterpCore<9>;

void expect_same(const Interp& a, const Interp& b, uint64_t clock) {
  ASSERT_EQ(a.state(), b.state()) << "clock " << clock;
  ASSERT_EQ(a.phase(), b.phase()) << "clock " << clock;
  for (int x = 0; x < 3; ++x) ASSERT_EQ(a.pos(x), b.pos(x)) << "axis " << x << ", clock " << clock;
  ASSERT_EQ(a.count(), b.count()) << "clock " << clock;
  ASSERT_EQ(a.seg_cnt(), b.seg_cnt()) << "clock " << clock;
  ASSERT_EQ(a.underrun(), b.underrun()) << "clock " << clock;
}

// Random segments into an interpolator's queue as room frees, a word now
// and then rather than every clock, so that the engine runs between.
struct SegFeeder {
  // total: segments to queue in all; one_in: a word goes in one clock in
  // this many; lines: two segments in three are lines (else any kind).
  SegFeeder(SegGen& g, int total_segments, uint32_t one_in_clocks, bool mostly_lines = false)
      : gen(g), total(total_segments), one_in(one_in_clocks), lines(mostly_lines) {}
  SegGen& gen;
  int total;
  uint32_t one_in;
  bool lines;
  Vec3 at{0, 0, 0};
  std::vector<uint32_t> words;
  int queued = 0;
  // The queue's word for this clock, if one goes in.
  void feed(std::mt19937_64& rng, int count, InterpIn& in) {
    if (words.empty() && queued < total && count < 3 * seg::SEG_WORDS) {
      const PlannedSegment p = lines && rng() % 3 ? gen.line(at) : gen.any(at);
      at = p.end;
      for (uint32_t w : seg::pack(p.seg)) words.push_back(w);
      ++queued;
    }
    if (!words.empty() && rng() % one_in == 0) {
      in.wr = true;
      in.wdata = words.front();
      words.erase(words.begin());
    }
  }
  bool more() const { return queued < total || !words.empty(); }
};

// Segments for a lone interpolator: feeds from lo to hi iterations a
// clock, lines up to max_line counts, arcs up to max_radius.
SegGen interp_segments(uint64_t seed, double lo, double hi, int64_t max_line, int64_t max_radius) {
  SegGen gen(seed);
  gen.min_rate = lo;
  gen.max_rate = hi;
  gen.max_line = max_line;
  gen.max_radius = max_radius;
  return gen;
}

Interp reset_interp() {
  Interp ip;
  ip.reset();
  return ip;
}

TEST(InterpTwinFastForward, RunSkipEqualsClocks) {
  uint64_t all_skipped = 0, all_clocks = 0;
  for (uint64_t seed : {11, 12, 13, 14}) {
    std::mt19937_64 rng(seed);
    // Slow feeds as well: long stretches without an iteration are what the
    // fast-forward skips; fast ones reach the rate that fires every tick.
    SegGen gen =
        seed == 14 ? interp_segments(seed, 0.5, 1.0, 40, 30) : interp_segments(seed, 0.001, 0.05, 40, 30);
    Interp ref, fast;
    ref.reset();
    fast.reset();
    SegFeeder feeder(gen, 60, 8);
    uint64_t clock = 0, skipped = 0;
    while (feeder.more() || ref.busy() || ref.count() > 0) {
      InterpIn in;
      feeder.feed(rng, ref.count(), in);
      in.hold = rng() % 20000 < 3;
      in.clr = rng() % 50000 == 0;
      const uint32_t q = fast.run_quiet(in);
      if (q > 0 && !in.wr) {
        const uint32_t n = rng() % 4 ? q : 1 + uint32_t(rng() % q);
        for (uint32_t i = 0; i < n; ++i) ref.clock(in);
        fast.skip_run(n);
        clock += n;
        skipped += n;
      } else {
        ref.clock(in);
        fast.clock(in);
        ++clock;
      }
      expect_same(ref, fast, clock);
      if (HasFatalFailure()) return;
      // Every register, the RAM and the read ports as well.
      ASSERT_TRUE(ref == fast) << "seed " << seed << ", clock " << clock;
      ASSERT_LT(clock, 400'000'000u) << "seed " << seed << ": the segments never finished";
    }
    std::printf("seed %llu: %llu clocks, %llu of them skipped, %d segments\n", (unsigned long long)seed,
                (unsigned long long)clock, (unsigned long long)skipped, feeder.queued);
    if (seed != 14) {
      EXPECT_GT(skipped, clock / 2) << "seed " << seed;
    }
    all_skipped += skipped;
    all_clocks += clock;
  }
  EXPECT_GT(all_skipped, all_clocks / 2);
}

// The rest of a running tick at once (InterpCore::finish_tick) and
// run_for(), which takes it where a tick fits, against clocking: from every
// few clocks of random lines, arcs and dwells at slow and fast feeds
// (iterations pending, a tick firing at every step it can start from),
// with holds, the whole state, the position and the clocks that moved it
// must be clocking's. finish_tick() refuses only a tick whose step 5 ends
// the segment.
TEST(InterpTwinFastForward, FinishTickEqualsClocks) {
  uint64_t ticks = 0, moving = 0, refused = 0, runs = 0;
  uint64_t from_step[Interp::TICK] = {};
  // The clocks (from 1) of n clocks of `slow` that moved the position.
  const auto clocked = [](Interp& slow, uint32_t n) {
    std::vector<uint32_t> moves;
    for (uint32_t i = 1; i <= n; ++i) {
      const int32_t before[3] = {slow.pos(0), slow.pos(1), slow.pos(2)};
      slow.clock(InterpIn{});
      if (slow.pos(0) != before[0] || slow.pos(1) != before[1] || slow.pos(2) != before[2])
        moves.push_back(i);
    }
    return moves;
  };
  for (uint64_t seed : {41, 42, 43}) {
    std::mt19937_64 rng(seed);
    SegGen gen =
        seed == 43 ? interp_segments(seed, 0.5, 1.0, 60, 40) : interp_segments(seed, 0.01, 0.3, 60, 40);
    Interp ip = reset_interp();
    SegFeeder feeder(gen, 50, 6);
    uint64_t clock = 0;
    while (feeder.more() || ip.busy() || ip.count() > 0) {
      InterpIn in;
      feeder.feed(rng, ip.count(), in);
      in.hold = rng() % 3000 == 0;
      if (in == InterpIn{} && ip.state() == Interp::ST_RUN && rng() % 3 == 0) {
        const int step = ip.step();
        Interp fast = ip, slow = ip;
        std::vector<uint32_t> moves;
        const auto note = [&](uint32_t i) { moves.push_back(i); };
        if (fast.finish_tick(0, note)) {
          ASSERT_EQ(clocked(slow, uint32_t(Interp::TICK - step)), moves)
              << "seed " << seed << ", clock " << clock;
          ASSERT_TRUE(slow == fast) << "seed " << seed << ", clock " << clock << ", from step " << step;
          ++ticks;
          ++from_step[step];
          moving += !moves.empty();
        } else {
          ASSERT_TRUE(fast == ip) << "seed " << seed << ", clock " << clock << ": refused, yet changed";
          ASSERT_LE(step, Interp::STEP_DECIDE);
          clocked(slow, uint32_t(Interp::STEP_DECIDE - step));
          ASSERT_TRUE(slow.ending()) << "seed " << seed << ", clock " << clock
                                     << ": refused a tick that goes on";
          ++refused;
        }
        Interp fast2 = ip, slow2 = ip;
        moves.clear();
        const uint32_t did = fast2.run_for(1 + uint32_t(rng() % 200), note);
        ASSERT_EQ(clocked(slow2, did), moves) << "seed " << seed << ", clock " << clock;
        ASSERT_TRUE(slow2 == fast2) << "seed " << seed << ", clock " << clock << ", run_for " << did;
        ++runs;
      }
      ip.clock(in);
      ++clock;
      ASSERT_LT(clock, 100'000'000u) << "seed " << seed << ": the segments never finished";
    }
  }
  std::printf("%llu ticks finished at once (%llu moving), %llu refused at their end, %llu run_for\n",
              (unsigned long long)ticks, (unsigned long long)moving, (unsigned long long)refused,
              (unsigned long long)runs);
  for (int s = 0; s < Interp::TICK; ++s) EXPECT_GT(from_step[s], 50u) << "from step " << s;
  EXPECT_GT(moving, 1000u);
  EXPECT_GT(refused, 20u);
}

// end_bound() is a lower bound: no running segment ends sooner than it said
// at any clock of its run. Lines and arcs (full circles among them, whose
// end point is the start), fast feeds (an iteration every tick, pending
// ones queued) and slow, with holds; and the bound is not idle: most clocks
// of a long segment have one of several ticks.
TEST(InterpTwinFastForward, EndBoundIsALowerBound) {
  uint64_t clocks_bounded = 0, clocks_run = 0;
  for (uint64_t seed : {31, 32, 33}) {
    std::mt19937_64 rng(seed);
    SegGen gen =
        seed == 33 ? interp_segments(seed, 0.7, 1.0, 200, 60) : interp_segments(seed, 0.02, 0.5, 200, 60);
    Interp ip = reset_interp();
    SegFeeder feeder(gen, 80, 4, true);
    int ended = 0;
    uint64_t clock = 0, latest = 0;  // latest: the latest clock a bound so far allowed the end at
    int seg = ip.seg_cnt();
    while (feeder.more() || ip.busy() || ip.count() > 0) {
      InterpIn in;
      feeder.feed(rng, ip.count(), in);
      in.hold = rng() % 5000 == 0;
      if (ip.state() == Interp::ST_RUN) {
        const uint32_t b = ip.end_bound();
        latest = std::max(latest, clock + b);
        clocks_bounded += b >= 2 * Interp::TICK;
        ++clocks_run;
      }
      ip.clock(in);
      ++clock;
      if (ip.seg_cnt() != seg) {  // a segment ended at this clock
        ASSERT_GE(clock, latest) << "seed " << seed << ": segment " << ended << " ended before its bound";
        seg = ip.seg_cnt();
        latest = 0;
        ++ended;
      }
      ASSERT_LT(clock, 400'000'000u) << "seed " << seed << ": the segments never finished";
    }
    EXPECT_GT(ended, 60) << "seed " << seed;
  }
  std::printf("%llu of %llu running clocks had a bound of two ticks or more\n",
              (unsigned long long)clocks_bounded, (unsigned long long)clocks_run);
  EXPECT_GT(clocks_bounded, clocks_run / 2);
}

using Core = MotionCore<2>;

// Segments for a core that closes its loops while they run: slow, short,
// XY only.
SegGen core_segments(uint64_t seed) {
  SegGen gen(seed);
  gen.min_rate = 0.001;
  gen.max_rate = 0.03;
  gen.max_line = 30;
  gen.max_radius = 20;
  gen.planes = false;
  return gen;
}

// Reset, gains, Ts and both axes enabled through the PID port, every core
// clocked alike; the drive allowed.
template <typename... More>
void configure(Core::In& in, uint32_t ts, Core& core, More&... more) {
  const auto clock = [&] {
    core.clock(in);
    (more.clock(in), ...);
  };
  in.rst = true;
  for (int i = 0; i < 3; ++i) clock();
  in.rst = false;
  const std::pair<uint8_t, uint32_t> cfg[] = {
      {0x00, (1u << 20) | (16u << 24)}, {0x10, (1u << 20) | (16u << 24)}, {0x0F, 1}, {0x1F, 1}, {0xF0, ts}};
  for (const auto& [addr, data] : cfg) {
    in.pid_we = true;
    in.pid_waddr = addr;
    in.pid_wdata = data;
    while (!core.outputs(true).pid_wready) clock();
    clock();
  }
  in.pid_we = false;
  in.drv_allow[0] = in.drv_allow[1] = true;
}

// Both encoders' pins for this clock: a count up or down in `edges` clocks
// of 3000 each, now and then both pins at once (an error) or the index; an
// index arm or error clear in one clock of `strobe` each.
void walk_encoders(std::mt19937_64& rng, Core::In& in, int64_t (&count)[2], uint64_t edges, uint64_t strobe) {
  for (int x = 0; x < 2; ++x) {
    in.enc_idx_arm[x] = rng() % strobe == 0;
    in.enc_err_clr[x] = rng() % strobe == 0;
    const uint64_t r = rng() % 3000;
    if (r < edges) count[x] += r < edges / 2 ? 1 : -1;
    const int q = int(count[x] & 3);
    in.enc_a[x] = q == 1 || q == 2;
    in.enc_b[x] = q >= 2;
    if (r == 61) in.enc_a[x] = !in.enc_a[x];  // both pins at once: an error
    if (r == 61) in.enc_b[x] = !in.enc_b[x];
    if (r == 62) in.enc_z[x] = !in.enc_z[x];
  }
}

// The motion core with a running interpolator: quiet()/skip() against
// clock(), the PID closing the loop on a still encoder; (seeds 23 to 26)
// quiet_busy()/skip_busy(), which let the interpolator iterate meanwhile;
// and (seeds 25 to 28) encoders that move, so that skips start while a
// decoder works through an edge (Let::settle): counts up and down, now and
// then both pins at once (an error) or the index, with an index arm or an
// error clear between. Seeds 27 and 28 let everything the co-simulation's
// jumps let (Let::drive and Let::sample: through the sweep's drive
// updates, up to the edge that raises the tick or done, the sample port
// following an address that changes now and then).
TEST(InterpTwinFastForward, MotionCoreSkipsWhileRunning) {
  for (uint64_t seed : {21, 22, 23, 24, 25, 26, 27, 28}) {
    const bool busy = seed >= 23, moving = seed >= 25, full = seed >= 27;
    const Core::Let all{false, true, true, true, true};
    uint64_t edges = 0;  // skips that ended raising the tick or done
    int64_t count[2] = {};
    uint64_t settling = 0;  // skips begun with a decoder not settled
    std::mt19937_64 rng(seed);
    SegGen gen = core_segments(seed);
    Core ref, fast;
    Core::In in;
    configure(in, 200, ref, fast);
    in.enc_filt[0] = uint32_t(seed % 4);
    in.enc_filt[1] = 5;
    Vec3 at{0, 0, 0};
    std::vector<uint32_t> words;
    for (int s = 0; s < 20; ++s) {
      const PlannedSegment p = gen.any(at);
      at = p.end;
      for (uint32_t w : seg::pack(p.seg)) words.push_back(w);
    }
    uint64_t clock = 0, skipped = 0;
    while ((!words.empty() || ref.interp().busy() || ref.interp().count() > 0) && clock < 200'000'000) {
      in.seg_wr = !words.empty() && rng() % 4 == 0 && ref.interp().count() < 300;
      in.seg_wdata = in.seg_wr ? words.front() : 0;
      if (in.seg_wr) words.erase(words.begin());
      if (moving) walk_encoders(rng, in, count, 60, 800);
      if (full && rng() % 64 == 0) in.smp_raddr = uint8_t(rng() % 32);
      const uint32_t lim = full   ? fast.quiet_limit_as(all)
                           : busy ? fast.quiet_limit_busy()
                                  : fast.quiet_limit();
      const uint32_t n = lim == 0 ? 0 : (rng() % 3 ? lim : 1 + uint32_t(rng() % lim));
      uint32_t did = 0;
      if (n > 0 && (full ? fast.quiet_as(in, n, all) : busy ? fast.quiet_busy(in, n) : fast.quiet(in, n))) {
        for (int x = 0; x < 2; ++x) {
          QuadIn qi;
          qi.filt_len = in.enc_filt[x];
          qi.a = in.enc_a[x];
          qi.b = in.enc_b[x];
          qi.z = in.enc_z[x];
          if (!fast.decoder(x).quiet(qi)) {
            ++settling;
            break;
          }
        }
        if (full) {
          did = fast.skip_busy_as(in, n, all, [](uint32_t) {});
          ASSERT_LE(did, n);
          edges += fast.pid().tick() || fast.pid().done();
        } else if (busy) {
          did = fast.skip_busy(in, n);
          ASSERT_LE(did, n);
        } else {
          fast.skip(n);
          did = n;
        }
        for (uint32_t i = 0; i < did; ++i) ref.clock(in);
        clock += did;
        skipped += did;
      }
      if (did == 0) {
        ref.clock(in);
        fast.clock(in);
        ++clock;
      }
      const auto a = ref.outputs(), b = fast.outputs();
      for (int x = 0; x < 2; ++x) {
        ASSERT_EQ(a.cmd[x], b.cmd[x]) << "clock " << clock;
        ASSERT_EQ(a.drv_u[x], b.drv_u[x]) << "clock " << clock;
        ASSERT_EQ(a.pwm[x], b.pwm[x]) << "clock " << clock;
      }
      ASSERT_EQ(a.seg_count, b.seg_count) << "clock " << clock;
      ASSERT_EQ(a.ip_seg_cnt, b.ip_seg_cnt) << "clock " << clock;
      ASSERT_EQ(ref.interp().phase(), fast.interp().phase()) << "clock " << clock;
      // Every register of every block.
      ASSERT_TRUE(ref == fast) << "seed " << seed << ", clock " << clock;
    }
    ASSERT_FALSE(ref.interp().busy()) << "seed " << seed << ": the segments never finished";
    std::printf(
        "seed %llu: %llu clocks, %llu of them skipped; %llu skips begun inside an edge, %llu ended raising "
        "the tick or done\n",
        (unsigned long long)seed, (unsigned long long)clock, (unsigned long long)skipped,
        (unsigned long long)settling, (unsigned long long)edges);
    EXPECT_GT(skipped, clock / 2) << "seed " << seed;
    if (moving) {
      EXPECT_GT(settling, 1000u) << "seed " << seed;
    }
    if (full) {
      EXPECT_GT(edges, 1000u) << "seed " << seed;
    }
  }
}

// A running core's queue, fed as the jump tests feed it: random segments
// planned on as the words run low, a word one clock in eight while the
// queue has room.
struct CoreFeed {
  SegGen& gen;
  Vec3 at{0, 0, 0};
  std::vector<uint32_t> words;
  void word(std::mt19937_64& rng, const Core& core, Core::In& in) {
    if (words.size() < 40) {
      const PlannedSegment p = gen.any(at);
      at = p.end;
      for (uint32_t w : seg::pack(p.seg)) words.push_back(w);
    }
    in.seg_wr = rng() % 8 == 0 && core.interp().count() < 100;
    in.seg_wdata = in.seg_wr ? words.front() : 0;
    if (in.seg_wr) words.erase(words.begin());
  }
};

// What the co-simulation's jumps rest on, against clock(): from random
// points of a running core (lines, arcs and dwells streamed in, encoders
// moving with glitches and index pulses, the drive allowed, overridden or
// written now and then, the sample port's address changing), the inputs
// held as a jump holds them: (1) drive_steps() gives each axis's drive
// value in every clock up to known_drive_clocks(); (2) skipping what
// quiet_as(.., Let with drive, sample and done) allows and clocking what
// quiet_but_pid() allows leaves the whole state that clocking leaves, no
// segment ends or loads meanwhile, and done comes at the same clocks
// (inside a stretch, at the clock done_in() told before it). Ts
// = 52 clocks is the latency itself: the tick and done at one edge.
TEST(InterpTwinFastForward, JumpsThroughSamplesEqualClocks) {
  // Jumps through the tick, and jumps that clock it (the looks again
  // between the stretches).
  const Core::Let through{false, true, true, true, true, true, true},
      to_tick{false, true, true, true, true, true};
  for (const uint32_t ts : {52u, 53u, 200u, 1207u}) {
    std::mt19937_64 rng(ts);
    SegGen gen = core_segments(ts);
    Core ref;
    Core::In in;
    configure(in, ts, ref);
    in.enc_filt[0] = ts % 4;
    in.enc_filt[1] = 3;
    CoreFeed feed{gen, {0, 0, 0}, {}};
    int64_t count[2] = {};
    uint64_t jumps = 0, changes = 0, cycled = 0, samples = 0, held = 0, looks = 0, agains = 0, inside = 0,
             ticks = 0;
    for (uint64_t clock = 0; clock < 150'000; ++clock) {
      feed.word(rng, ref, in);
      if (rng() % 20'000 == 0)
        for (int x = 0; x < 2; ++x) {
          in.drv_allow[x] = rng() % 4 != 0;
          in.drv_ovr[x] = rng() % 4 == 0;
        }
      for (int x = 0; x < 2; ++x) in.drv_ovr_we[x] = rng() % 50'000 == 0;
      in.drv_ovr_val = int16_t(rng());
      if (rng() % 500 == 0) in.smp_raddr = uint8_t(rng() % 32);
      walk_encoders(rng, in, count, 20, 5000);
      if (rng() % 97 == 0) {
        const Core::Let all = jumps % 2 == 0 ? through : to_tick;
        // The inputs a jump holds: no segment word, strobe or override write.
        Core::In h = in;
        h.seg_wr = false;
        h.seg_wdata = 0;
        for (int x = 0; x < 2; ++x) h.enc_idx_arm[x] = h.enc_err_clr[x] = h.drv_ovr_we[x] = false;
        const Core::DriveSteps ds[2] = {ref.drive_steps(h, 0), ref.drive_steps(h, 1)};
        const uint32_t known = std::min<uint32_t>(ref.known_drive_clocks(), 3000);
        Core clocked = ref;
        for (uint32_t c = 0; c < known; ++c) {
          for (int x = 0; x < 2; ++x)
            ASSERT_EQ(clocked.drv_u(x), ds[x].at(c))
                << "Ts " << ts << ", clock " << clock << "+" << c << ", axis " << x;
          clocked.clock(h);
        }
        for (int x = 0; x < 2; ++x) changes += ds[x].change < known;
        // The jump's advance over a random part of that, against clocking.
        const uint32_t n = 1 + uint32_t(rng() % known);
        Core fast = ref;
        std::vector<uint32_t> fast_done;
        uint32_t did = 0;
        bool others = false;  // the first look's checks but the PID's held
        while (did < n) {
          const uint32_t q = std::min(n - did, fast.quiet_limit_as(all));
          // After it, with the inputs held and only skips and clocks of
          // what it allowed, the PID's checks alone tell the same.
          bool now = false;
          const int kind = fast.quiet_or_pid(h, q, all, &now);
          if (others) {
            ASSERT_TRUE(now) << "Ts " << ts << ", clock " << clock << "+" << did;
            ASSERT_EQ(fast.quiet_or_pid_again(h, q, all), kind)
                << "Ts " << ts << ", clock " << clock << "+" << did;
            ++agains;
          } else if (did == 0) {
            others = now;
          }
          // quiet_or_pid() is the two looks at once, with this Let and
          // with those whose checks depend on the stretch's length.
          for (const Core::Let let :
               {through, to_tick, Core::Let{false, true, true, false, true, true},
                Core::Let{false, false, true, true, true}, Core::Let{false, true, true, true, true}}) {
            const uint32_t l = std::min(n - did, fast.quiet_limit_as(let));
            ASSERT_EQ(fast.quiet_or_pid(h, l, let), l > 0 && fast.quiet_as(h, l, let) ? Core::kQuiet
                                                    : fast.quiet_but_pid(h, let)      ? Core::kPidClock
                                                                                      : 0)
                << "Ts " << ts << ", clock " << clock << "+" << did;
            ++looks;
          }
          if (q > 0 && fast.quiet_as(h, q, all)) {
            // Done's clock, when the stretch goes through it.
            const uint32_t d = fast.done_in(), t = fast.pid().tick() ? 0 : fast.pid().timer();
            const uint32_t m = fast.skip_busy_as(h, q, all, [](uint32_t) {});
            if (d < m) {
              fast_done.push_back(did + d);
              ++inside;
            }
            ticks += t < m;
            did += m;
            if (m > 0) continue;
          }
          const bool quiet_one = fast.quiet_limit_as(all) > 0 && fast.quiet_as(h, 1, all);
          if (fast.interp().ending() || (!quiet_one && !fast.quiet_but_pid(h, all))) break;
          if (fast.pid().done()) fast_done.push_back(did);
          fast.clock(h);
          ++did;
          ++cycled;
        }
        Core slow = ref;
        std::vector<uint32_t> slow_done;
        const int level = slow.interp().count(), segments = slow.interp().seg_cnt();
        for (uint32_t i = 0; i < did; ++i) {
          if (slow.pid().done()) slow_done.push_back(i);
          slow.clock(h);
        }
        ASSERT_EQ(slow.interp().count(), level) << "Ts " << ts << ", clock " << clock;
        ASSERT_EQ(slow.interp().seg_cnt(), segments) << "Ts " << ts << ", clock " << clock;
        ASSERT_TRUE(slow == fast) << "Ts " << ts << ", clock " << clock << ", " << did << " of " << n;
        ASSERT_EQ(slow_done, fast_done) << "Ts " << ts << ", clock " << clock;
        samples += fast_done.size();
        held += did;
        ++jumps;
      }
      ref.clock(in);
    }
    std::printf(
        "Ts %u: %llu jumps over %llu clocks, %llu drive updates inside, %llu clocks cycled, %llu samples, "
        "%llu looks, %llu looks again, %llu dones and %llu ticks inside stretches\n",
        ts, (unsigned long long)jumps, (unsigned long long)held, (unsigned long long)changes,
        (unsigned long long)cycled, (unsigned long long)samples, (unsigned long long)looks,
        (unsigned long long)agains, (unsigned long long)inside, (unsigned long long)ticks);
    EXPECT_GT(jumps, 1000u);
    // Ts = latency: the tick and done at one edge, which ends a stretch.
    if (ts > 52) {
      EXPECT_GT(inside, 30u);
    }
    EXPECT_GT(changes, 30u);
    EXPECT_GT(samples, 30u);
    EXPECT_GT(agains, 100u);
    EXPECT_GT(ticks, 20u);
  }
}

// The edges a jump's stretches take in (MotionCore::foldable and the
// skip_busy_as() that changes pins), against clocking with the pins changing
// at the same clocks: from random points of a running core, the inputs held
// as a jump holds them but for counts of one step each, at random clocks
// (some closer than a decoder settles, with an index now and then, and
// with the filter on for some Ts, which no fold may take). The whole state
// and the clocks of done must be clocking's.
TEST(InterpTwinFastForward, JumpsTakeEdgesAsClocks) {
  using PinChange = Core::PinChange;
  const Core::Let all{false, true, true, true, true, true, true};
  for (const uint32_t ts : {52u, 200u, 1207u}) {
    std::mt19937_64 rng(ts + 1);
    SegGen gen = core_segments(ts);
    Core ref;
    Core::In in;
    configure(in, ts, ref);
    in.enc_filt[0] = ts == 200 ? 2 : 1;
    in.enc_filt[1] = 0;
    CoreFeed feed{gen, {0, 0, 0}, {}};
    int64_t count[2] = {};
    uint64_t jumps = 0, folded = 0, refused = 0;
    const auto pins = [](Core::In& h, int x, int64_t c) {
      const int q = int(c & 3);
      h.enc_a[x] = q == 1 || q == 2;
      h.enc_b[x] = q >= 2;
      h.enc_z[x] = c % 64 == 0;
    };
    for (uint64_t clock = 0; clock < 100'000; ++clock) {
      feed.word(rng, ref, in);
      for (int x = 0; x < 2; ++x) {
        if (rng() % 400 == 0) count[x] += rng() % 2 ? 1 : -1;
        pins(in, x, count[x]);
      }
      if (rng() % 97 == 0) {
        Core::In h = in;
        h.seg_wr = false;
        h.seg_wdata = 0;
        const uint32_t n = 1 + uint32_t(rng() % std::min<uint32_t>(ref.known_drive_clocks(), 3000));
        // The counts: one step of one axis at a clock, 1 to 40 clocks apart.
        struct Edge {
          uint32_t clock;
          int axis;
          int64_t count;
        };
        std::vector<Edge> edges;
        int64_t c[2] = {count[0], count[1]};
        for (uint32_t t = 1 + uint32_t(rng() % 40); t < n; t += 1 + uint32_t(rng() % 40)) {
          const int x = int(rng() % 2);
          c[x] += rng() % 4 == 0 ? -1 : 1;
          edges.push_back(Edge{t, x, c[x]});
        }
        Core fast = ref, slow = ref;
        std::vector<uint32_t> fast_done, slow_done;
        Core::In hf = h;
        size_t e = 0;
        uint32_t did = 0;
        while (did < n) {
          for (; e < edges.size() && edges[e].clock == did; ++e) pins(hf, edges[e].axis, edges[e].count);
          const uint32_t q = std::min(n - did, fast.quiet_limit_as(all));
          if (q > 0 && fast.quiet_as(hf, q, all)) {
            std::vector<PinChange> ch;
            for (size_t i = e; i < edges.size() && edges[i].clock < did + q; ++i) {
              Core::In p = hf;
              pins(p, edges[i].axis, edges[i].count);
              ch.push_back(PinChange{edges[i].clock - did, edges[i].axis, p.enc_a[edges[i].axis],
                                     p.enc_b[edges[i].axis], p.enc_z[edges[i].axis]});
            }
            const size_t f = fast.foldable(hf, ch.data(), ch.size());
            const uint32_t len = f < ch.size() ? ch[f].clock : q;
            refused += f < ch.size();
            QuadOut seen[2];
            for (int x = 0; x < 2; ++x) seen[x] = fast.decoder(x).out();
            const uint32_t d = fast.done_in();
            const uint32_t m = fast.skip_busy_as(
                hf, len, all, [](uint32_t) {}, ch.data(), f);
            if (d < m) fast_done.push_back(did + d);
            // What a reader sees between ticks stays (Let::settle).
            for (int x = 0; x < 2; ++x) {
              const QuadOut o = fast.decoder(x).out();
              ASSERT_TRUE(o.err == seen[x].err && o.err_cnt == seen[x].err_cnt &&
                          o.idx_pos == seen[x].idx_pos && o.idx_seen == seen[x].idx_seen)
                  << "Ts " << ts << ", clock " << clock << "+" << did << ", axis " << x;
            }
            did += m;
            for (; e < edges.size() && edges[e].clock < did; ++e) {
              pins(hf, edges[e].axis, edges[e].count);
              ++folded;
            }
            if (m > 0) continue;
          }
          const bool quiet_one = fast.quiet_limit_as(all) > 0 && fast.quiet_as(hf, 1, all);
          if (fast.interp().ending() || (!quiet_one && !fast.quiet_but_pid(hf, all))) break;
          if (fast.pid().done()) fast_done.push_back(did);
          fast.clock(hf);
          ++did;
        }
        Core::In hs = h;
        e = 0;
        for (uint32_t i = 0; i < did; ++i) {
          for (; e < edges.size() && edges[e].clock == i; ++e) pins(hs, edges[e].axis, edges[e].count);
          if (slow.pid().done()) slow_done.push_back(i);
          slow.clock(hs);
        }
        ASSERT_TRUE(slow == fast) << "Ts " << ts << ", clock " << clock << ", " << did << " of " << n;
        ASSERT_EQ(slow_done, fast_done) << "Ts " << ts << ", clock " << clock;
        ++jumps;
      }
      ref.clock(in);
    }
    std::printf("Ts %u: %llu jumps, %llu edges taken inside stretches, %llu stretches cut at an edge\n", ts,
                (unsigned long long)jumps, (unsigned long long)folded, (unsigned long long)refused);
    EXPECT_GT(jumps, 500u);
    // Both happen: edges taken in, and stretches cut where one is not
    // clean (too close to the last, or filtered).
    EXPECT_GT(folded, 800u) << "Ts " << ts;
    EXPECT_GT(refused, 30u) << "Ts " << ts;
  }
}

// The decoder's fast-forwards against step(): a random walk of the pins
// (edges, glitches, index pulses, dwells of every length), the sample
// strobe and the other strobes now and then. At every clock a quiet
// decoder's skip(1), one quiet but for the sample's skip_sampled(), and a
// settling one's skip_settling() must leave the whole state that step()
// leaves (the age and velocity that only the decoder's own ports show
// included).
TEST(QuadTwinFastForward, QuietClocksEqualSteps) {
  using Decoder = QuadDecoder<8, 8, 32, 16, false, false>;
  std::mt19937_64 rng(7);
  Decoder dec;
  QuadIn in;
  in.filt_len = 1;
  int64_t count = 0;
  std::mt19937_64 pick(11);  // the held stretches' lengths, apart from the walk
  uint64_t quiet = 0, sampled = 0, settled = 0, settled_at_once = 0, whole_edges = 0;
  for (uint64_t t = 0; t < 400000; ++t) {
    in.sample = rng() % 16 == 0;
    in.idx_arm = rng() % 500 == 0;
    in.err_clr = rng() % 700 == 0;
    in.latch = rng() % 900 == 0;
    if (rng() % 5000 == 0) in.filt_len = uint32_t(rng() % 4);
    // Pins: an edge in one clock in twelve, a glitch now and then.
    if (rng() % 12 == 0) count += rng() % 2 ? 1 : -1;
    const int phase = int(((count % 4) + 4) % 4);
    in.a = phase == 1 || phase == 2;
    in.b = phase >= 2;
    in.z = ((count % 40) + 40) % 40 == 0;
    if (rng() % 97 == 0) in.a = !in.a;
    Decoder stepped = dec;
    stepped.step(in);
    if (dec.quiet(in)) {
      Decoder fast = dec;
      fast.skip(1);
      ASSERT_TRUE(fast == stepped) << "skip(1), clock " << t;
      ++quiet;
    } else if (in.sample && dec.quiet_but_sample(in)) {
      Decoder fast = dec;
      fast.skip_sampled();
      ASSERT_TRUE(fast == stepped) << "skip_sampled(), clock " << t;
      ++sampled;
    } else if (const uint32_t c = dec.settle_clocks(in); c != Decoder::kUnsettled) {
      Decoder fast = dec;
      fast.skip_settling(in, 1);
      ASSERT_TRUE(fast == stepped) << "skip_settling(), clock " << t;
      ++settled;
      // The whole settling at once, with the pins held: the clocks it
      // said, and n of them (past it too) as n steps leave the decoder.
      Decoder held = dec;
      uint32_t to_quiet = 0;
      while (!held.quiet(in) && to_quiet <= Decoder::kMaxSettle) {
        held.step(in);
        ++to_quiet;
      }
      ASSERT_EQ(c, to_quiet) << "settle_clocks(), clock " << t;
      const uint32_t n = 1 + uint32_t(pick() % 12);
      held = dec;
      for (uint32_t i = 0; i < n; ++i) held.step(in);
      fast = dec;
      fast.skip_settling(in, n);
      ASSERT_TRUE(fast == held) << "skip_settling(" << n << "), clock " << t;
      ++settled_at_once;
      if (c == 4 && n >= 4) ++whole_edges;
    }
    dec = stepped;
  }
  std::printf(
      "%llu quiet clocks, %llu sampled quiet clocks, %llu settling clocks, %llu settlings at once (%llu "
      "whole edges) checked\n",
      (unsigned long long)quiet, (unsigned long long)sampled, (unsigned long long)settled,
      (unsigned long long)settled_at_once, (unsigned long long)whole_edges);
  EXPECT_GT(quiet, 10000u);
  EXPECT_GT(sampled, 1000u);
  EXPECT_GT(settled, 1000u);
  EXPECT_GT(whole_edges, 1000u);
}

}  // namespace
}  // namespace mc::test
