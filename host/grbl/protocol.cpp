#include "host/grbl/protocol.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <utility>

namespace mc::grbl {
namespace {

// Grbl status codes the engine answers itself (the interpreter's errors
// carry their own).
constexpr int kOk = 0;
constexpr int kBadNumberFormat = 2;
constexpr int kInvalidStatement = 3;
constexpr int kSettingDisabled = 5;
constexpr int kNotIdle = 8;
constexpr int kGcodeLock = 9;
constexpr int kOverflow = 11;
constexpr int kLineLengthExceeded = 14;
constexpr int kTravelExceeded = 15;
constexpr int kInvalidJog = 16;
constexpr int kUnsupportedCommand = 20;

// Alarm codes raised here.
constexpr int kAlarmSoftLimit = 2;
constexpr int kAlarmAbortCycle = 3;
constexpr int kAlarmProbeContact = 5;
constexpr int kAlarmHomingReset = 6;

// Grbl's refresh schedule of WCO: and Ov: (config.h): every Nth report.
constexpr int kWcoBusy = 30, kWcoIdle = 10, kOvrBusy = 20, kOvrIdle = 10;

// Grbl's override limits and steps (config.h).
constexpr int kFeedMin = 10, kFeedMax = 200, kSpindleMin = 10, kSpindleMax = 200;

// Past this much unread input the server stops reading (see input_room()).
constexpr size_t kMaxBacklog = size_t(1) << 16;

constexpr double kMmPerInch = 25.4;

// Fixed decimals, never "-0.000".
std::string fixed(double v, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

// Grbl's number reader for `$` commands: [+-]digits[.digits].
bool read_number(const std::string& s, size_t& i, double& v) {
  const size_t start = i;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  bool digits = false;
  while (i < s.size() && (std::isdigit(static_cast<unsigned char>(s[i])) || s[i] == '.')) {
    digits = digits || s[i] != '.';
    ++i;
  }
  if (!digits) {
    i = start;
    return false;
  }
  v = std::strtod(s.substr(start, i - start).c_str(), nullptr);
  return true;
}

// The N word at the start of a cleaned line, 0 when none.
int line_number(const std::string& line) {
  if (line.empty() || line[0] != 'N') return 0;
  size_t i = 1;
  double v = 0;
  if (!read_number(line, i, v) || v < 0 || v > 2147483647.0) return 0;
  return int(v);
}

template <class T>
const T* find_op(const std::vector<gcode::CanonCall>& calls) {
  for (const auto& c : calls)
    if (const T* p = std::get_if<T>(&c.op)) return p;
  return nullptr;
}

}  // namespace

Engine::Engine(Backend& backend, EngineOptions options)
    : backend_(backend), opt_(std::move(options)), stored_(opt_.stored) {
  backend_.configure(stored_.settings);
  soft_reset(true);
}

size_t Engine::input_room() const {
  return rx_.size() >= kMaxBacklog ? 0 : kMaxBacklog - rx_.size();
}

std::string Engine::greeting() const {
  std::string s = "\r\n" + std::string(kBanner) + "\r\n";
  if (alarm_) s += "[MSG:'$H'|'$X' to unlock]\r\n";
  return s;
}

std::string Engine::take_output() {
  std::string s;
  s.swap(out_);
  return s;
}

void Engine::receive(std::string_view bytes) {
  for (const char ch : bytes) {
    const auto c = static_cast<uint8_t>(ch);
    if (c == '?' || c == '!' || c == '~' || c == 0x18 || c >= 0x80)
      realtime(c);
    else
      rx_.push_back(ch);
  }
}

void Engine::poll() {
  while (auto e = backend_.poll_event()) handle_event(*e);
  if (jog_cancelled_ && backend_.status().motion != Motion::jog && backend_.drained()) {
    // A cancelled jog stops short of its target: the parser continues from
    // where the machine is (Grbl's gc_sync_position).
    interp_.set_machine_position(backend_.status().position);
    jog_cancelled_ = false;
  }
  advance_pending();
  run_lines();
}

// --- real-time bytes ---------------------------------------------------------

void Engine::realtime(uint8_t c) {
  const bool locked = alarm_ || check_ || sleep_;
  Overrides o = ovr_;
  switch (c) {
    case 0x18:
      soft_reset(false);
      return;
    case '?':
      status_report();
      return;
    case '!': {
      if (locked) return;
      const Motion m = backend_.status().motion;
      if (m == Motion::jog) {
        // A hold during a jog cancels it, as Grbl.
        backend_.jog_cancel();
        jog_cancelled_ = true;
      } else if (m != Motion::homing) {
        backend_.feed_hold();
      }
      return;
    }
    case '~':
      if (!locked && backend_.status().motion == Motion::held) backend_.cycle_start();
      return;
    case 0x85:
      if (backend_.status().motion == Motion::jog) {
        backend_.jog_cancel();
        jog_cancelled_ = true;
      }
      return;
    case 0x90:
      o.feed = 100;
      break;
    case 0x91:
      o.feed += 10;
      break;
    case 0x92:
      o.feed -= 10;
      break;
    case 0x93:
      o.feed += 1;
      break;
    case 0x94:
      o.feed -= 1;
      break;
    case 0x95:
      o.rapid = 100;
      break;
    case 0x96:
      o.rapid = 50;
      break;
    case 0x97:
      o.rapid = 25;
      break;
    case 0x99:
      o.spindle = 100;
      break;
    case 0x9A:
      o.spindle += 10;
      break;
    case 0x9B:
      o.spindle -= 10;
      break;
    case 0x9C:
      o.spindle += 1;
      break;
    case 0x9D:
      o.spindle -= 1;
      break;
    default:
      return;  // other bytes >= 0x80: dropped, as Grbl's serial interrupt does
  }
  o.feed = std::clamp(o.feed, kFeedMin, kFeedMax);
  o.spindle = std::clamp(o.spindle, kSpindleMin, kSpindleMax);
  set_overrides(o);
}

void Engine::set_overrides(const Overrides& o) {
  if (o == ovr_) return;
  ovr_ = o;
  backend_.set_overrides(ovr_);
  ovr_counter_ = 0;  // show the new values in the next report
}

gcode::Vec3 Engine::wco() const {
  const gcode::PersistentData& d = interp_.data();
  const gcode::ModalState& m = interp_.modal();
  gcode::Vec3 w = d.coord_offsets[size_t(std::clamp(m.coord_system, 0, 8))];
  for (size_t i = 0; i < 3; ++i)
    if (d.g92_applied) w[i] += d.g92[i];
  w[2] += m.tool_length_mm;
  return w;
}

std::string Engine::axes(const gcode::Vec3& v) const {
  const bool inch = stored_.settings.report_inches;
  std::string s;
  for (size_t i = 0; i < 3; ++i) {
    if (i) s += ',';
    s += inch ? fixed(v[i] / kMmPerInch, 4) : fixed(v[i], 3);
  }
  return s;
}

std::string Engine::state() const {
  if (sleep_) return "Sleep";
  if (alarm_) return "Alarm";
  if (check_) return "Check";
  switch (backend_.status().motion) {
    case Motion::idle:
      return "Idle";
    case Motion::run:
      return "Run";
    case Motion::holding:
      return "Hold:1";
    case Motion::held:
      return "Hold:0";
    case Motion::jog:
      return "Jog";
    case Motion::homing:
      return "Home";
  }
  return "Idle";
}

bool Engine::busy() const {
  if (sleep_ || alarm_ || check_) return false;
  return backend_.status().motion != Motion::idle;
}

void Engine::status_report() {
  const Status s = backend_.status();
  const Settings& set = stored_.settings;
  const bool inch = set.report_inches;
  const gcode::Vec3 w = wco();
  gcode::Vec3 pos = s.position;
  const bool mpos = (set.report_mask & 1) != 0;
  if (!mpos)
    for (size_t i = 0; i < 3; ++i) pos[i] -= w[i];
  std::string r = "<" + state() + (mpos ? "|MPos:" : "|WPos:") + axes(pos);
  if (set.report_mask & 2) {
    const size_t rx_free = rx_.size() >= kRxBufferSize ? 0 : kRxBufferSize - rx_.size();
    r += "|Bf:" + std::to_string(s.blocks_free) + "," + std::to_string(rx_free);
  }
  if (s.line_number > 0) r += "|Ln:" + std::to_string(s.line_number);
  r += "|FS:" + (inch ? fixed(s.feed_mm_min / kMmPerInch, 1) : fixed(s.feed_mm_min, 0)) + "," +
       fixed(s.spindle_rpm, 0);
  const Pins& p = s.pins;
  std::string pins;
  if (p.probe) pins += 'P';
  for (size_t i = 0; i < 3; ++i)
    if (p.limit[i]) pins += "XYZ"[i];
  if (p.door) pins += 'D';
  if (p.reset) pins += 'R';
  if (p.hold) pins += 'H';
  if (p.start) pins += 'S';
  if (!pins.empty()) r += "|Pn:" + pins;
  if (!s.handwheel.empty()) r += "|HW:" + s.handwheel;

  // WCO: and Ov: on Grbl's schedule: every 10th report when idle, every
  // 30th/20th when busy, at once after a change, never both in one report.
  const bool is_busy = busy();
  if (wco_counter_ > 0) {
    --wco_counter_;
  } else {
    wco_counter_ = (is_busy ? kWcoBusy : kWcoIdle) - 1;
    if (ovr_counter_ == 0) ovr_counter_ = 1;
    r += "|WCO:" + axes(w);
  }
  if (ovr_counter_ > 0) {
    --ovr_counter_;
  } else {
    ovr_counter_ = (is_busy ? kOvrBusy : kOvrIdle) - 1;
    r += "|Ov:" + std::to_string(ovr_.feed) + "," + std::to_string(ovr_.rapid) + "," +
         std::to_string(ovr_.spindle);
    std::string acc;
    if (s.spindle > 0) acc += 'S';
    if (s.spindle < 0) acc += 'C';
    if (s.flood) acc += 'F';
    if (s.mist) acc += 'M';
    if (!acc.empty()) r += "|A:" + acc;
  }
  emit(r + ">");
}

// --- resets and alarms ---------------------------------------------------------

void Engine::soft_reset(bool power_up) {
  if (power_up) {
    // Grbl's HOMING_INIT_LOCK: a machine that homes must home (or be
    // unlocked) before it moves.
    alarm_ = stored_.settings.homing;
  } else {
    const Motion m = backend_.status().motion;
    // A reset while moving (or decelerating into a hold) may lose position:
    // Grbl raises an alarm. A completed hold (Hold:0) is a safe stop.
    const int code = m == Motion::homing                                              ? kAlarmHomingReset
                     : (m == Motion::run || m == Motion::holding || m == Motion::jog) ? kAlarmAbortCycle
                                                                                      : 0;
    backend_.soft_reset();
    if (code) {
      emit("ALARM:" + std::to_string(code));
      alarm_ = true;
    }
    if (sleep_) alarm_ = true;
  }
  critical_ = check_ = sleep_ = jog_cancelled_ = false;
  rx_.clear();
  line_.clear();
  in_paren_ = in_semicolon_ = overflow_ = false;
  pending_.reset();
  startup_.clear();
  ovr_ = Overrides{};
  backend_.set_overrides(ovr_);
  wco_counter_ = ovr_counter_ = 0;
  probe_position_ = {};
  probe_ok_ = probe_seen_ = false;
  // Grbl's gc_init: modal state to defaults, offsets from EEPROM, G92 cleared.
  gcode::Options o;
  o.start = backend_.status().position;
  o.data = stored_.offsets;
  o.data.g92 = {};
  o.data.g92_applied = true;
  interp_ = gcode::Interpreter(o);
  out_ += greeting();
  if (!alarm_) {
    for (const std::string& l : stored_.startup)
      if (!l.empty()) startup_.push_back(l);
  }
}

void Engine::alarm(int code, const std::string& message, bool critical) {
  backend_.soft_reset();
  emit("ALARM:" + std::to_string(code));
  if (!message.empty()) emit("[MSG:" + message + "]");
  if (critical) emit("[MSG:Reset to continue]");
  alarm_ = true;
  critical_ = critical_ || critical;
  // The line waiting for the backend will not run; it still gets its one
  // answer so that a sender's count stays right.
  if (pending_) {
    reply(kGcodeLock, pending_->prefix);
    pending_.reset();
  }
  interp_.set_machine_position(backend_.status().position);
}

void Engine::handle_event(const Event& e) {
  if (const auto* a = std::get_if<AlarmEvent>(&e)) {
    alarm(a->code, a->message, a->critical);
  } else if (const auto* p = std::get_if<ProbeEvent>(&e)) {
    probe_position_ = p->position;
    probe_ok_ = p->contact;
    probe_seen_ = true;
    interp_.set_machine_position(p->position);
  } else if (const auto* m = std::get_if<MessageEvent>(&e)) {
    emit("[MSG:" + m->text + "]");
  }
}

// --- lines ---------------------------------------------------------------------

void Engine::reply(int code, const std::string& prefix) {
  out_ += prefix + (code == kOk ? std::string("ok") : "error:" + std::to_string(code)) + "\r\n";
  if (prefix.empty()) ++answered_;
}

void Engine::run_lines() {
  while (!pending_ && !critical_ && !sleep_) {
    if (!startup_.empty()) {
      const std::string l = startup_.front();
      startup_.pop_front();
      execute(l, ">" + l + ":");
      continue;
    }
    // Grbl's protocol_main_loop: characters leave the buffer as they are
    // read; blanks, control characters, '/' and comments are dropped,
    // letters upper-cased. '\r' and '\n' each end a line.
    bool eol = false;
    while (!rx_.empty() && !eol) {
      const char c = rx_.front();
      rx_.pop_front();
      if (c == '\n' || c == '\r') {
        eol = true;
      } else if (in_paren_ || in_semicolon_ || overflow_) {
        if (c == ')') in_paren_ = false;
      } else if (static_cast<unsigned char>(c) <= ' ' || c == '/') {
      } else if (c == '(') {
        in_paren_ = true;
      } else if (c == ';') {
        in_semicolon_ = true;
      } else if (line_.size() >= kLineMax) {
        overflow_ = true;
      } else {
        line_ += char(std::toupper(static_cast<unsigned char>(c)));
      }
    }
    if (!eol) return;
    const std::string line = std::move(line_);
    const bool overflow = overflow_;
    line_.clear();
    in_paren_ = in_semicolon_ = overflow_ = false;
    if (overflow)
      reply(kOverflow);
    else if (line.empty())
      reply(kOk);
    else
      execute(line, "");
  }
}

void Engine::execute(const std::string& line, const std::string& prefix) {
  if (line[0] == '$') {
    const int code = system_command(line);
    if (code >= 0) reply(code, prefix);
    return;
  }
  if (alarm_ || sleep_ || backend_.status().motion == Motion::jog) {
    reply(kGcodeLock, prefix);
    return;
  }
  gcode_line(line, prefix);
}

bool Engine::soft_limit_violated(const std::vector<gcode::CanonCall>& calls) const {
  if (!stored_.settings.soft_limits) return false;
  // Grbl's machine space is -max_travel..0 (homing sets 0 at the top end);
  // here the top end is the machine's travel_max, so that the defaults are
  // exactly the machine TOML's travel.
  const Settings& set = stored_.settings;
  const auto outside = [&](const gcode::Vec3& p) {
    for (size_t i = 0; i < 3; ++i)
      if (p[i] > set.travel_top_mm[i] || p[i] < set.travel_top_mm[i] - set.max_travel_mm[i]) return true;
    return false;
  };
  for (const auto& c : calls) {
    const bool bad = std::visit(
        [&](const auto& op) {
          using T = std::decay_t<decltype(op)>;
          if constexpr (std::is_same_v<T, gcode::StraightTraverse> ||
                        std::is_same_v<T, gcode::StraightFeed> || std::is_same_v<T, gcode::ArcFeed> ||
                        std::is_same_v<T, gcode::StraightProbe>)
            return outside(op.end);
          else
            return false;
        },
        c.op);
    if (bad) return true;
  }
  return false;
}

void Engine::gcode_line(const std::string& line, const std::string& prefix) {
  sync_to_handwheel();
  const gcode::PersistentData before = interp_.data();
  const gcode::Vec3 wco_before = wco();
  gcode::LineResult res = interp_.execute_line(line, ++line_count_);
  if (!res.ok()) {
    reply(res.error->grbl_code ? res.error->grbl_code : kUnsupportedCommand, prefix);
    return;
  }
  if (check_) {  // $C: parsed and checked, nothing moves, nothing is stored
    reply(kOk, prefix);
    return;
  }
  if (soft_limit_violated(res.calls)) {
    // As Grbl: nothing of the line runs, the machine stops where it is and
    // only a reset continues (the line gets no answer: the reset clears the
    // sender's count).
    alarm(kAlarmSoftLimit, "", true);
    return;
  }
  const gcode::PersistentData& after = interp_.data();
  if (after.coord_offsets != before.coord_offsets || after.g28 != before.g28 || after.g30 != before.g30)
    persist();

  Pending p;
  p.prefix = prefix;
  p.sub.id = next_id_++;
  p.sub.line_number = line_number(line);
  for (const auto& c : res.calls) {
    if (std::holds_alternative<gcode::Dwell>(c.op)) p.sync = true;
    if (std::holds_alternative<gcode::StraightProbe>(c.op)) p.sync = p.probe = true;
    if (std::holds_alternative<gcode::ChangeTool>(c.op)) p.sync = p.pause = true;
    if (const auto* s = std::get_if<gcode::ProgramStop>(&c.op)) {
      if (s->kind == gcode::StopKind::pause) p.sync = p.pause = true;
      if (s->kind == gcode::StopKind::end || s->kind == gcode::StopKind::end_rewind)
        p.sync = p.program_end = true;
    }
  }
  // Grbl's FORCE_BUFFER_SYNC_DURING_WCO_CHANGE: a new offset answers once
  // the moves before it are done, so WPos never mixes old and new.
  if (wco() != wco_before) {
    p.sync = true;
    wco_counter_ = 0;
  }
  p.sub.calls = std::move(res.calls);
  if (p.sub.calls.empty() && !p.sync) {
    reply(kOk, prefix);
    return;
  }
  if (p.probe) probe_seen_ = false;
  pending_ = std::move(p);
  advance_pending();
}

void Engine::advance_pending() {
  if (!pending_) return;
  Pending& p = *pending_;
  if (!p.submitted) {
    if (!p.sub.calls.empty()) {
      if (!backend_.ready()) return;
      backend_.submit(p.sub);
    }
    p.submitted = true;
  }
  if (p.sync) {
    if (p.probe && !probe_seen_) return;
    if (!backend_.drained() || backend_.status().motion == Motion::homing) return;
  }
  const Pending done = std::move(p);
  pending_.reset();
  if (done.probe) {
    const auto* probe = find_op<gcode::StraightProbe>(done.sub.calls);
    const bool must_touch = probe && (probe->mode == gcode::ProbeMode::toward_error ||
                                      probe->mode == gcode::ProbeMode::away_error);
    if (!probe_ok_ && must_touch) {
      backend_.soft_reset();
      emit("ALARM:" + std::to_string(kAlarmProbeContact));
      alarm_ = true;
    }
    emit("[PRB:" + axes(probe_position_) + ":" + (probe_ok_ ? "1" : "0") + "]");
  }
  if (done.pause) backend_.feed_hold();  // M0/M6: Hold:0 until `~`
  if (done.program_end) {
    set_overrides(Overrides{});  // Grbl's RESTORE_OVERRIDES_AFTER_PROGRAM_END
    wco_counter_ = 0;
    emit("[MSG:Pgm End]");
  }
  reply(kOk, done.prefix);
  if (done.homing) {
    // Machine zero moved: the parser continues from the new MPos.
    interp_.set_machine_position(backend_.status().position);
    alarm_ = false;
    for (const std::string& l : stored_.startup)
      if (!l.empty()) startup_.push_back(l);
  }
}

void Engine::persist() {
  stored_.offsets = interp_.data();
  stored_.offsets.g92 = {};
  stored_.offsets.g92_applied = true;
  if (opt_.save) opt_.save(stored_);
}

// --- $ commands ----------------------------------------------------------------

void Engine::sync_to_handwheel() {
  // The wheel moved the machine since the parser last knew where it was:
  // the next line starts there, as after a jog.
  const Status s = backend_.status();
  if (!s.handwheel.empty()) interp_.set_machine_position(s.position);
}

int Engine::jog(const std::string& line) {
  sync_to_handwheel();
  if (line.size() < 3 || line[2] != '=') return kInvalidStatement;
  const std::string words = line.substr(3);
  // Only G20/G21, G90/G91, G53, the axes, F and N (Grbl's jog rules).
  std::string n_word, rest;
  for (size_t i = 0; i < words.size();) {
    const char letter = words[i++];
    size_t j = i;
    double v = 0;
    if (!read_number(words, j, v)) return kInvalidJog;
    const std::string word = words.substr(i - 1, j - i + 1);
    i = j;
    if (letter == 'G') {
      if (v != 20 && v != 21 && v != 90 && v != 91 && v != 53) return kInvalidJog;
    } else if (letter == 'N') {
      n_word = word;
      continue;
    } else if (letter != 'X' && letter != 'Y' && letter != 'Z' && letter != 'F') {
      return kInvalidJog;
    }
    rest += word;
  }
  if (rest.find('F') == std::string::npos) return gcode::grbl::undefined_feed_rate;
  // The words run as a G1 on a copy of the parser: offsets, units and
  // distance mode apply as in the program, and nothing modal changes.
  gcode::Interpreter copy = interp_;
  gcode::LineResult r = copy.execute_line(n_word + "G94G1" + rest, ++line_count_);
  if (!r.ok()) return r.error->grbl_code ? r.error->grbl_code : kInvalidJog;
  const auto* feed = find_op<gcode::StraightFeed>(r.calls);
  if (!feed) return kOk;  // no axis moves
  if (soft_limit_violated(r.calls)) return kTravelExceeded;
  Pending p;
  p.sub.id = next_id_++;
  p.sub.line_number = line_number(n_word);
  p.sub.jog = true;
  p.sub.calls.push_back({line_count_, *feed});
  interp_.set_machine_position(feed->end);  // the next jog starts from this one's end
  pending_ = std::move(p);
  advance_pending();
  return -1;
}

// $LEV: the bed's height map (not Grbl's: motionctl serve --level FILE
// gives it), reported as [LEV:ON|OFF,NxM,Xa..b,Yc..d,FILE]; $LEV=1 and
// $LEV=0 turn levelling on and off for the lines that follow.
int Engine::levelling(const std::string& l) {
  if (l == "$LEV") {
    const std::string map = backend_.height_map();
    emit("[LEV:" + std::string(backend_.levelling() ? "ON" : "OFF") + (map.empty() ? "" : "," + map) + "]");
    return kOk;
  }
  if (l != "$LEV=0" && l != "$LEV=1") return kInvalidStatement;
  if (alarm_) return kNotIdle;
  return backend_.set_levelling(l.back() == '1');
}

// $MPG: the handwheel (not Grbl's), reported as [MPG:X10] or [MPG:OFF];
// $MPG=X10 puts it on X at 10 counts a detent, $MPG=0 turns it off. The
// status report shows the axis it jogs as HW:X,10.
int Engine::handwheel(const std::string& l) {
  const std::string now = backend_.mpg();
  if (now.empty()) return kSettingDisabled;
  if (l == "$MPG") {
    emit("[MPG:" + now + "]");
    return kOk;
  }
  if (l.size() < 6 || l[4] != '=') return kInvalidStatement;
  return backend_.set_mpg(l.substr(5));
}

int Engine::system_command(const std::string& l) {
  Settings& set = stored_.settings;
  const Motion m = backend_.status().motion;
  const bool idle = !alarm_ && !check_ && !sleep_ && m == Motion::idle;
  if (l.size() == 1) {
    emit("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]");
    return kOk;
  }
  const char c = l[1];
  if (c == 'J') {
    if (!(idle || (!alarm_ && !check_ && !sleep_ && m == Motion::jog))) return kNotIdle;
    return jog(l);
  }
  if (c == '$' || c == 'G' || c == 'C' || c == 'X') {
    if (l.size() != 2) return kInvalidStatement;
    switch (c) {
      case '$':
        if (!alarm_ && !check_ && m != Motion::idle && m != Motion::jog) return kNotIdle;
        for (int n : setting_numbers()) emit(format_setting(set, n));
        return kOk;
      case 'G':
        emit(gcode::modal_report(interp_.modal()));
        return kOk;
      case 'C':
        if (check_) {
          // Leaving check mode resets, so the parser forgets the checked program.
          emit("[MSG:Disabled]");
          reply(kOk);
          soft_reset(false);
          return -1;
        }
        if (!idle) return kNotIdle;
        check_ = true;
        emit("[MSG:Enabled]");
        return kOk;
      default:  // 'X'
        if (alarm_) {
          emit("[MSG:Caution: Unlocked]");
          alarm_ = false;
        }
        return kOk;
    }
  }
  // The rest needs Idle or Alarm.
  if (!(idle || (alarm_ && !sleep_))) return kNotIdle;
  if (l.rfind("$LEV", 0) == 0) return levelling(l);
  if (l.rfind("$MPG", 0) == 0) return handwheel(l);
  switch (c) {
    case '#': {
      if (l.size() != 2) return kInvalidStatement;
      const gcode::PersistentData& d = interp_.data();
      for (size_t i = 0; i < 6; ++i)
        emit("[G" + std::to_string(54 + i) + ":" + axes(d.coord_offsets[i]) + "]");
      emit("[G28:" + axes(d.g28) + "]");
      emit("[G30:" + axes(d.g30) + "]");
      emit("[G92:" + axes(d.g92_applied ? d.g92 : gcode::Vec3{}) + "]");
      const double tlo = interp_.modal().tool_length_mm;
      emit("[TLO:" + (set.report_inches ? fixed(tlo / kMmPerInch, 4) : fixed(tlo, 3)) + "]");
      emit("[PRB:" + axes(probe_position_) + ":" + (probe_ok_ ? "1" : "0") + "]");
      return kOk;
    }
    case 'H': {
      if (!set.homing) return kSettingDisabled;
      if (l.size() != 2) return kInvalidStatement;
      const int code = backend_.home(7);
      if (code != kOk) return code;
      Pending p;
      p.submitted = p.sync = p.homing = true;
      pending_ = std::move(p);
      advance_pending();
      return -1;
    }
    case 'S':
      if (l != "$SLP") return kInvalidStatement;
      backend_.soft_reset();
      sleep_ = true;
      emit("[MSG:Sleeping]");
      return kOk;
    case 'I':
      if (l.size() == 2) {
        emit("[VER:1.1h.20190830:" + stored_.build_info + "]");
        emit("[OPT:VNM," + std::to_string(backend_.planner_blocks()) + "," + std::to_string(kRxBufferSize) +
             "]");
        return kOk;
      }
      if (l[2] != '=') return kInvalidStatement;
      stored_.build_info = l.substr(3);
      persist();
      return kOk;
    case 'R': {
      if (l.size() != 6 || l.compare(0, 5, "$RST=") != 0) return kInvalidStatement;
      const char what = l[5];
      if (what == '$' || what == '*') stored_.settings = opt_.defaults.settings;
      if (what == '#' || what == '*') stored_.offsets = opt_.defaults.offsets;
      if (what == '*') {
        stored_.startup = opt_.defaults.startup;
        stored_.build_info = opt_.defaults.build_info;
      }
      if (what != '$' && what != '#' && what != '*') return kInvalidStatement;
      emit("[MSG:Restoring defaults]");
      if (opt_.save) opt_.save(stored_);
      backend_.configure(stored_.settings);
      reply(kOk);
      soft_reset(false);
      return -1;
    }
    case 'N': {
      if (l.size() == 2) {
        for (size_t i = 0; i < stored_.startup.size(); ++i)
          emit("$N" + std::to_string(i) + "=" + stored_.startup[i]);
        return kOk;
      }
      if (!idle) return kNotIdle;  // storing needs Idle: no motion from an alarm
      size_t i = 2;
      double n = 0;
      if (!read_number(l, i, n)) return kBadNumberFormat;
      if (i >= l.size() || l[i] != '=') return kInvalidStatement;
      const int index = int(std::trunc(n));
      if (index < 0 || index >= int(stored_.startup.size())) return kInvalidStatement;
      const std::string block = l.substr(i + 1);
      if (block.size() > kLineMax - 3) return kLineLengthExceeded;
      if (!block.empty()) {
        // Checked, not run (Grbl runs it to check it).
        gcode::Interpreter copy = interp_;
        const gcode::LineResult r = copy.execute_line(block, 0);
        if (!r.ok()) return r.error->grbl_code ? r.error->grbl_code : kUnsupportedCommand;
      }
      stored_.startup[size_t(index)] = block;
      if (opt_.save) opt_.save(stored_);
      return kOk;
    }
    default: {
      size_t i = 1;
      double n = 0, v = 0;
      if (!read_number(l, i, n)) return kBadNumberFormat;
      if (i >= l.size() || l[i] != '=') return kInvalidStatement;
      ++i;
      if (!read_number(l, i, v)) return kBadNumberFormat;
      if (i != l.size() || n > 255 || n < 0) return kInvalidStatement;
      const int number = int(std::trunc(n));
      const int code = set_setting(set, number, v);
      if (code != kOk) return code;
      backend_.configure(set);
      if (opt_.save) opt_.save(stored_);
      if (number == 10 || number == 13) wco_counter_ = 0;
      return kOk;
    }
  }
}

}  // namespace mc::grbl
