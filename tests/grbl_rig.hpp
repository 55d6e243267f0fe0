// A Grbl engine on the dry-run machine, driven in board time: what the
// protocol tests send, what comes back, and the machine's clock stepped by
// the test (never the wall clock).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "host/grbl/dry_run_backend.hpp"
#include "host/grbl/protocol.hpp"
#include "host/grbl/settings.hpp"

namespace mc::grbl::test {

inline Stored test_defaults() {
  Stored s;
  s.settings.counts_per_mm = {400, 400, 400};
  s.settings.max_rate_mm_min = {6000, 6000, 6000};
  s.settings.accel_mm_s2 = {500, 500, 500};
  s.settings.max_travel_mm = {200, 200, 200};
  return s;
}

struct Rig {
  explicit Rig(const Stored& stored = test_defaults(), int blocks = 4) : backend(blocks) {
    backend.keep_received(true);
    EngineOptions o;
    o.stored = stored;
    o.defaults = test_defaults();
    o.save = [this](const Stored& s) { saves.push_back(s); };
    engine = std::make_unique<Engine>(backend, o);
    out = engine->take_output();
  }

  // Sends bytes, polls once, returns the replies.
  std::string send(const std::string& bytes) {
    engine->receive(bytes);
    engine->poll();
    return engine->take_output();
  }
  // Runs the machine for `seconds` in 1 ms steps, polling after each.
  std::string run(double seconds) {
    std::string s;
    for (double t = 0; t < seconds; t += 1e-3) {
      backend.advance(1e-3);
      engine->poll();
      s += engine->take_output();
    }
    return s;
  }
  // Runs until the engine has produced `needle`, for at most max_s of board time.
  std::string run_until(const std::string& needle, double max_s = 60) {
    std::string s;
    for (double t = 0; t < max_s && s.find(needle) == std::string::npos; t += 1e-3) {
      backend.advance(1e-3);
      engine->poll();
      s += engine->take_output();
    }
    return s;
  }
  // Runs until the machine is idle with nothing queued.
  std::string run_until_idle(double max_s = 60) {
    std::string s;
    for (double t = 0; t < max_s; t += 1e-3) {
      backend.advance(1e-3);
      engine->poll();
      s += engine->take_output();
      if (backend.drained() && backend.status().motion == Motion::idle && engine->buffered() == 0) break;
    }
    return s;
  }
  // A status report alone (the `?` reply without its CR LF).
  std::string status() {
    std::string r = send("?");
    EXPECT_GE(r.size(), 2u);
    if (r.size() >= 2) r.resize(r.size() - 2);
    return r;
  }

  DryRunBackend backend;
  std::unique_ptr<Engine> engine;
  std::vector<Stored> saves;
  std::string out;  // the power-up output
};

inline size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + what.size())) ++n;
  return n;
}

}  // namespace mc::grbl::test
