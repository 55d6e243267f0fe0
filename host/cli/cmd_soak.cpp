// motionctl sim soak: the link soak of issue 18 (sim/vboard/link_soak.hpp),
// a G-code job looped over a line that flips and drops bytes, with the
// board's segment queue checked against what the host sent.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "sim/vboard/link_soak.hpp"

namespace mc::host::cli {
namespace {

std::atomic<bool> g_soak_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

extern "C" void on_soak_signal(int) {
  g_soak_stop.store(true);
}

struct SoakCliOptions {
  std::string job = "examples/profile.nc";
  std::string board_seconds = "3600";
  std::string engine = "twin";
  std::string flip = "1e-3", drop = "1e-3";
  uint32_t seed = 1;
  bool json = false, quiet = false;
};

void print_result(const mc::sim::SoakResult& r, const mc::sim::SoakOptions& so) {
  const mc::sim::SegmentTally& t = r.segs;
  std::printf("soak: %s on the %s, %d passes%s\n", r.job.c_str(), mc::sim::board_engine_name(r.engine),
              r.passes, r.stopped ? " (stopped on request)" : "");
  std::printf("  time: %.1f s of board time in %.1f s wall (%.2fx real time), %.1f s CPU\n", r.board_s,
              r.wall_s, r.wall_s > 0 ? r.board_s / r.wall_s : 0.0, r.cpu_s);
  std::printf(
      "  injected (seed %u): to the board %llu bytes, %llu flipped, %llu dropped; to the host %llu bytes, "
      "%llu flipped, %llu dropped\n",
      unsigned(so.seed), (unsigned long long)r.to_board.bytes, (unsigned long long)r.to_board.flipped,
      (unsigned long long)r.to_board.dropped, (unsigned long long)r.to_host.bytes,
      (unsigned long long)r.to_host.flipped, (unsigned long long)r.to_host.dropped);
  std::printf("  segments: %llu sent, %llu applied: %llu lost, %llu doubled, %llu reordered, %llu foreign\n",
              (unsigned long long)t.sent, (unsigned long long)t.applied, (unsigned long long)t.lost,
              (unsigned long long)t.doubled, (unsigned long long)t.reordered, (unsigned long long)t.foreign);
  const LinkCounters& l = r.link;
  std::printf(
      "  host: %llu requests, %llu timeouts (each a retransmission), %llu DUP replies, %llu stale replies; "
      "received %llu good frames, %llu bad CRC, %llu framing errors, %llu junk bytes\n",
      (unsigned long long)l.requests, (unsigned long long)l.retransmits, (unsigned long long)l.dups,
      (unsigned long long)l.stale, (unsigned long long)l.rx.frames, (unsigned long long)l.rx.crc,
      (unsigned long long)l.rx.framing, (unsigned long long)l.rx.junk_bytes);
  std::printf(
      "  board (16-bit counters, stop at 65535): %u bad CRC, %u framing errors, %u refused (FULL here), "
      "%u duplicates, %u junk bytes\n",
      r.board_crc, r.board_framing, r.board_nak, r.board_dup, r.board_junk);
  std::printf("  underruns: %d; fault at the end: %s\n", r.underruns, r.fault ? "yes" : "none");
  std::printf("%s\n", r.clean() ? "PASS: 0 lost, 0 doubled, 0 reordered" : "FAIL");
}

void print_json(const mc::sim::SoakResult& r, const mc::sim::SoakOptions& so) {
  nlohmann::ordered_json j;
  j["job"] = r.job;
  j["engine"] = mc::sim::board_engine_name(r.engine);
  j["seed"] = so.seed;
  j["flip_rate"] = so.flip_rate;
  j["drop_rate"] = so.drop_rate;
  j["passes"] = r.passes;
  j["stopped"] = r.stopped;
  j["board_s"] = r.board_s;
  j["wall_s"] = r.wall_s;
  j["cpu_s"] = r.cpu_s;
  j["segments"] = {{"sent", r.segs.sent},
                   {"applied", r.segs.applied},
                   {"lost", r.segs.lost},
                   {"doubled", r.segs.doubled},
                   {"reordered", r.segs.reordered},
                   {"foreign", r.segs.foreign},
                   {"partial_words", r.segs.partial}};
  j["injected"] = {
      {"to_board",
       {{"bytes", r.to_board.bytes}, {"flipped", r.to_board.flipped}, {"dropped", r.to_board.dropped}}},
      {"to_host",
       {{"bytes", r.to_host.bytes}, {"flipped", r.to_host.flipped}, {"dropped", r.to_host.dropped}}}};
  const LinkCounters& l = r.link;
  j["host"] = {{"requests", l.requests},   {"timeouts", l.retransmits},    {"dup_replies", l.dups},
               {"stale_replies", l.stale}, {"frames", l.rx.frames},        {"crc", l.rx.crc},
               {"framing", l.rx.framing},  {"junk_bytes", l.rx.junk_bytes}};
  j["board"] = {{"crc", r.board_crc},
                {"framing", r.board_framing},
                {"refused", r.board_nak},
                {"duplicates", r.board_dup},
                {"junk_bytes", r.board_junk}};
  j["underruns"] = r.underruns;
  j["fault"] = r.fault;
  j["clean"] = r.clean();
  std::cout << j.dump(2) << '\n';
}

void soak(const SoakCliOptions& o) {
  mc::sim::SoakOptions so;
  so.job = o.job;
  so.board_s = parse_duration(o.board_seconds, "--board-seconds");
  so.engine = mc::sim::parse_board_engine(o.engine, "--engine");
  so.flip_rate = parse_number(o.flip, "--flip");
  so.drop_rate = parse_number(o.drop, "--drop");
  so.seed = o.seed;
  so.stop = &g_soak_stop;
  struct sigaction sa {};
  sa.sa_handler = on_soak_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  auto last = std::chrono::steady_clock::now();
  if (!o.quiet)
    so.progress = [&](const mc::sim::SoakResult& r) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last < std::chrono::seconds(30)) return;
      last = now;
      std::fprintf(stderr,
                   "soak: %.0f of %.0f s board time, %.0f s wall, pass %d: %llu segments, %llu lost, %llu "
                   "doubled, %llu reordered; %llu timeouts\n",
                   r.board_s, so.board_s, r.wall_s, r.passes, (unsigned long long)r.segs.applied,
                   (unsigned long long)r.segs.lost, (unsigned long long)r.segs.doubled,
                   (unsigned long long)r.segs.reordered, (unsigned long long)r.link.retransmits);
    };
  const mc::sim::SoakResult r = mc::sim::run_link_soak(machine(), so);
  if (o.json)
    print_json(r, so);
  else
    print_result(r, so);
  if (!r.clean())
    throw std::runtime_error("the soak lost, doubled or reordered segments (or the board faulted)");
}

}  // namespace

void add_soak_command(CLI::App& sim) {
  auto o = std::make_shared<SoakCliOptions>();
  CLI::App* cmd = sim.add_subcommand(
      "soak", "Link soak: a G-code job looped over a line with byte errors; counts lost, doubled, reordered");
  cmd->footer(
      "The virtual board in process (board time, deterministic for a seed), the link through a line that\n"
      "flips a random bit of a byte with probability --flip and drops a byte with probability --drop, each\n"
      "way. The job (planned with the machine config, --config before the command) runs whole, again and\n"
      "again, until --board-seconds of board time have passed; every segment the board's queue took is held\n"
      "against what the host sent. Prints the tally and the link's counters; exits 1 unless 0 segments were\n"
      "lost, doubled or reordered. SIGINT ends it after the pass under way. docs/reliability.md has "
      "figures.");
  cmd->add_option("--job", o->job, "G-code program (default examples/profile.nc)")->type_name("FILE");
  cmd->add_option("--board-seconds", o->board_seconds, "Board time to run (default 3600)")->type_name("TIME");
  cmd->add_option("--engine", o->engine,
                  "twin: the board's C++ twin (default, fast); rtl: the Verilated board")
      ->type_name("twin|rtl");
  cmd->add_option("--flip", o->flip, "Probability of a bit flip per byte, each way (default 1e-3)")
      ->type_name("P");
  cmd->add_option("--drop", o->drop, "Probability of a dropped byte, each way (default 1e-3)")
      ->type_name("P");
  cmd->add_option("--seed", o->seed, "Seed of the injected errors (default 1)");
  cmd->add_flag("--json", o->json, "The result as one JSON object");
  cmd->add_flag("--quiet", o->quiet, "No progress lines");
  cmd->callback([o] { soak(*o); });
}

}  // namespace mc::host::cli
