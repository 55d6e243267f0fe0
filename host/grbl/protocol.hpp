// The Grbl 1.1 protocol engine: bytes from a sender in, replies out, a
// Backend (backend.hpp) behind it. Pure: no I/O, no clock; the server
// (server.hpp) moves the bytes and calls poll() when anything may have
// changed, and tests drive it byte by byte.
//
// What a sender sees, as from Grbl 1.1h (docs/grbl.md has the details):
//  - real-time bytes act the moment they arrive, even inside a line or a
//    comment: `?` status report, `!` feed hold, `~` cycle start, 0x18 soft
//    reset, 0x85 jog cancel, 0x90..0x9D overrides; other bytes >= 0x80 are
//    dropped;
//  - the other bytes queue in a 128-byte receive buffer and are read one line
//    at a time: spaces, control characters and comments dropped, letters
//    upper-cased, at most 79 characters (error:11 beyond);
//  - each line gets exactly one `ok` or `error:N`, and a line's `ok` comes
//    when it is in the backend's queue (or, for G4, probes, M0/M2/M30 and
//    offset changes, when the queue has drained): a sender that counts the
//    bytes of unacknowledged lines against 128 never overflows the buffer;
//  - `$` commands, alarms (ALARM:N), feedback ([MSG:...], [PRB:...]) and the
//    banner after a reset, in Grbl's words.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "host/gcode/interpreter.hpp"
#include "host/grbl/backend.hpp"
#include "host/grbl/settings.hpp"

namespace mc::grbl {

inline constexpr const char* kBanner = "Grbl 1.1h ['$' for help]";
inline constexpr size_t kRxBufferSize = 128;  // Grbl's serial receive buffer
inline constexpr size_t kLineMax = 79;        // Grbl's LINE_BUFFER_SIZE - 1

struct EngineOptions {
  Stored stored;    // settings, start-up blocks and offsets at power-up
  Stored defaults;  // what $RST restores
  // Called with everything persistent whenever a command changed it.
  std::function<void(const Stored&)> save;
};

class Engine {
 public:
  // Powers up: the banner, then the start-up blocks (or the alarm lock when
  // homing is enabled, as Grbl).
  Engine(Backend& backend, EngineOptions options);

  // Bytes from the sender.
  void receive(std::string_view bytes);
  // Runs what can run now: backend events, then lines from the receive
  // buffer until one has to wait for the backend.
  void poll();
  // The replies produced so far, handed over once.
  std::string take_output();
  // What a sender that has just connected is shown, as when opening a serial
  // port resets an Arduino: the banner (and the unlock hint in an alarm). For
  // that sender only; the machine does not reset.
  std::string greeting() const;

  // Bytes waiting in the receive buffer. A sender that ignores flow control
  // can push past kRxBufferSize; the caller stops reading its input once
  // input_room() is 0, so that nothing is ever dropped.
  size_t buffered() const { return rx_.size(); }
  size_t input_room() const;

  // Grbl's state word: "Idle", "Run", "Hold:0", "Alarm", ...
  std::string state() const;
  const gcode::Interpreter& interpreter() const { return interp_; }
  const Stored& stored() const { return stored_; }
  const Overrides& overrides() const { return ovr_; }
  // Lines answered so far (ok or error), for servers' logs.
  uint64_t lines_answered() const { return answered_; }

 private:
  // A line read from the buffer that has to wait for the backend.
  struct Pending {
    Submission sub;  // calls to submit (none: only wait for the drain)
    bool submitted = false;
    bool sync = false;   // the ok waits until the backend has drained
    bool probe = false;  // a probe result must arrive first
    bool pause = false;  // M0/M6: hold after the drain
    bool program_end = false;
    bool homing = false;
    std::string prefix;  // ">line:" for a start-up block
  };

  void realtime(uint8_t c);
  void status_report();
  void soft_reset(bool power_up);
  void alarm(int code, const std::string& message, bool critical);
  void handle_event(const Event& e);
  // Reads and runs lines until one waits or the buffer has no full line.
  void run_lines();
  void execute(const std::string& line, const std::string& prefix);
  void gcode_line(const std::string& line, const std::string& prefix);
  int system_command(const std::string& line);
  int levelling(const std::string& line);
  int handwheel(const std::string& line);
  void sync_to_handwheel();
  int jog(const std::string& line);
  void advance_pending();
  void reply(int code, const std::string& prefix = "");
  void emit(const std::string& text) { out_ += text + "\r\n"; }
  void persist();
  void set_overrides(const Overrides& o);
  gcode::Vec3 wco() const;
  std::string axes(const gcode::Vec3& v) const;
  bool busy() const;
  bool soft_limit_violated(const std::vector<gcode::CanonCall>& calls) const;

  Backend& backend_;
  EngineOptions opt_;
  Stored stored_;
  gcode::Interpreter interp_;
  std::deque<char> rx_;
  std::string line_;  // the line being read, cleaned
  bool in_paren_ = false, in_semicolon_ = false, overflow_ = false;
  std::optional<Pending> pending_;
  std::deque<std::string> startup_;  // start-up blocks still to run
  std::string out_;
  bool alarm_ = false;          // locked: g-code refused until $X, $H or reset
  bool critical_ = false;       // nothing but reset and `?` until reset
  bool check_ = false;          // $C
  bool sleep_ = false;          // $SLP
  bool jog_cancelled_ = false;  // resync the parser once the jog stopped
  Overrides ovr_;
  int wco_counter_ = 0, ovr_counter_ = 0;
  gcode::Vec3 probe_position_{};
  bool probe_ok_ = false;
  bool probe_seen_ = false;
  uint64_t next_id_ = 1;
  int line_count_ = 0;
  uint64_t answered_ = 0;
};

}  // namespace mc::grbl
