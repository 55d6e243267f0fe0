// Test harness for quad_decoder: the twin alone, an encoder waveform in
// continuous time sampled the way the synchronizer's first flop samples it,
// and a bench that drives either the twin or the C/RTL co-simulation
// (quad_cosim.hpp) from the waveform.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <random>
#include <sstream>
#include <string>

#include "hls/quad_decoder.hpp"

namespace mc::test {

// The RTL's default parameters, and a build with every width small so that
// the saturations happen in a short test (tests/rtl.cmake builds the RTL
// with the same -G values).
using QuadDefault = QuadDecoder<>;
using QuadSmall = QuadDecoder<5, 2, 4, 4>;
using QuadIdxRam = QuadDecoder<4, 16, 32, 16, true>;  // the board's build

inline uint64_t env_count(const char* name, uint64_t dflt) {
  const char* v = std::getenv(name);
  return v ? std::strtoull(v, nullptr, 10) : dflt;
}

inline std::string describe(const QuadOut& o) {
  std::ostringstream os;
  os << "pos=" << o.pos << " idx_pos=" << o.idx_pos << " armed=" << o.idx_armed << " seen=" << o.idx_seen
     << " err=" << o.err << " err_cnt=" << o.err_cnt << " vel=" << o.vel << " age=" << o.age << " abz=" << o.a
     << o.b << o.z;
  return os.str();
}

// The twin alone, for the fast property runs. Twin is a QuadDecoder<...>.
template <typename Twin>
class QuadTwinSimT {
 public:
  using TwinT = Twin;
  explicit QuadTwinSimT(uint32_t) {}
  QuadOut cycle(const QuadIn& in) { return twin_.step(in); }
  int mismatches() const { return 0; }

 private:
  Twin twin_;
};

// Width of the metastable window around a clock edge, in clock periods
// either side: an input edge this close to the sampling instant may be seen
// in this clock or the next. Real iCE40 flops need far less; this is margin.
constexpr double kAperture = 0.02;

// The shortest spacing between edges (clock periods) that filter length L
// counts without loss, for a waveform whose A-to-B spacing alternates
// between T(1-e) and T(1+e) (e = phase error / 90 degrees): the edges of A and
// B must land in different clocks, and each level must cover max(L, 1)
// clocks, both allowing for the metastable window ap on each side.
inline double spacing_limit(int L, double e, double ap) {
  return std::max((1 + 2 * ap) / (1 - e), std::max(L, 1) / 2.0 + ap);
}

// An encoder's three outputs in continuous time (unit: clock periods; clock
// edge k samples at time k). Motion is a sequence of quadrature edges, each
// +-1 count of the true position; any channel can also toggle without
// motion (the index, noise). Forward (truth counting up) is A leading B:
// AB = 00, 10, 11, 01.
class EncoderWave {
 public:
  explicit EncoderWave(uint64_t seed, double aperture = kAperture) : rng_(seed), ap_(aperture) {}

  // One count of motion at time t.
  void edge(double t, int dir) {
    const int q = int(((truth_ % 4) + 4) % 4);
    // Between phases q and q+1 A moves when q is even.
    const int from = dir > 0 ? q : (q + 3) % 4;
    toggle(from % 2 == 0 ? 0 : 1, t);
    truth_ += dir;
  }
  // A level change on channel ch (0 A, 1 B, 2 Z) that is not motion.
  void toggle(int ch, double t) {
    auto& d = tr_[ch];
    d.insert(std::upper_bound(d.begin(), d.end(), t), t);
    last_ = std::max(last_, t);
  }
  void pulse(int ch, double t, double w) {
    toggle(ch, t);
    toggle(ch, t + w);
  }

  // What the first synchronizer flop captures at the clock edge at time tk.
  void sample(double tk, QuadIn& in) {
    bool v[3];
    for (int c = 0; c < 3; ++c) {
      auto& d = tr_[c];
      while (!d.empty() && d.front() <= tk - ap_) {
        lv_[c] = !lv_[c];
        d.pop_front();
      }
      v[c] = lv_[c];
      if (!d.empty() && d.front() < tk + ap_) v[c] = coin_(rng_) ? !lv_[c] : lv_[c];
    }
    in.a = v[0];
    in.b = v[1];
    in.z = v[2];
  }

  int64_t truth() const { return truth_; }
  double last() const { return last_; }  // time of the latest scheduled change
  bool level(int ch) const { return lv_[ch] != (tr_[ch].size() % 2 == 1); }  // after all changes
  double aperture() const { return ap_; }

 private:
  std::mt19937_64 rng_;
  std::bernoulli_distribution coin_{0.5};
  double ap_;
  std::deque<double> tr_[3];
  bool lv_[3] = {false, false, false};
  int64_t truth_ = 0;
  double last_ = 0;
};

// A Sim (QuadTwinSimT or QuadCosimT), an encoder waveform and the decoder's
// inputs. Strobes set in `in` last one clock.
template <typename Sim>
class QuadBench {
 public:
  explicit QuadBench(uint32_t seed, double aperture = kAperture) : sim(seed), wave(seed, aperture) {}

  QuadOut clock() {
    wave.sample(double(now), in);
    out = sim.cycle(in);
    in.pos_load = in.idx_arm = in.idx_disarm = in.err_clr = in.sample = in.latch = false;
    ++now;
    return out;
  }
  void run(uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) clock();
  }
  // Pin to pos_o, with margin for a metastable sample.
  int latency() const { return std::max<int>(int(in.filt_len & 0xFFFF), 1) + 4; }
  // Until every scheduled change has reached the outputs.
  void drain() {
    while (double(now) < wave.last() + 1) clock();
    run(uint64_t(latency()));
  }
  // A time half-way between two clock edges (so sampled without doubt), at
  // least about `after` clocks past now and every scheduled change.
  double next_time(double after = 1.5) const {
    return std::floor(std::max(double(now), wave.last()) + after) + 0.5;
  }
  // n counts of motion in direction dir, spacing T, from t0 (default: next_time()).
  double move_at(int n, int dir, double T, double t0) {
    for (int i = 0; i < n; ++i) wave.edge(t0 + i * T, dir);
    return t0 + n * T;
  }
  double move(int n, int dir, double T) { return move_at(n, dir, T, next_time()); }
  int32_t truth32() const { return int32_t(uint32_t(uint64_t(wave.truth()))); }

  Sim sim;
  EncoderWave wave;
  QuadIn in;
  QuadOut out;
  uint64_t now = 0;  // clocks run; the next one samples the pins at this time
};

// One rate trial: n edges at spacing T with phase error e (A-to-B spacing
// T(1-e), B-to-A T(1+e)) through b's decoder at its present filter length,
// in bursts of `burst` edges, each at a new random phase to the clock and in
// a random direction: a T commensurate with the clock visits only a few
// phases in one burst, and a limit must hold at all of them. Between bursts
// the encoder rests longer than the filter. Errors are cleared first.
struct RateTrial {
  bool exact;  // the decoder moved exactly as far as the waveform
  bool err;
};
template <typename Sim>
RateTrial rate_trial(QuadBench<Sim>& b, double T, double e, int n, int burst, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0, 1);
  b.in.err_clr = true;
  b.clock();
  const int32_t base = b.out.pos;
  const int64_t tbase = b.wave.truth();
  for (int i = 0; i < n; i += burst) {
    const int dir = (rng() & 1) ? 1 : -1;
    double t = b.next_time(std::max<uint32_t>(b.in.filt_len, 1) + 2) + phase(rng);
    for (int k = 0; k < burst && i + k < n; ++k) {
      b.wave.edge(t, dir);
      // The short gap follows the edge of A when moving forward.
      const bool a_moved = ((b.wave.truth() % 4) + 4) % 4 % 2 == (dir > 0 ? 1 : 0);
      t += T * (a_moved ? 1 - e : 1 + e);
    }
  }
  b.drain();
  const int32_t moved = int32_t(uint32_t(b.out.pos) - uint32_t(base));
  return {moved == int32_t(uint32_t(uint64_t(b.wave.truth() - tbase))), b.out.err};
}

}  // namespace mc::test
