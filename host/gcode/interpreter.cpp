#include "host/gcode/interpreter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "host/gcode/block.hpp"

namespace mc::gcode {
namespace {

constexpr double kMmPerInch = 25.4;
// Whole-number words (T, arc P turns) up to this: an int holds it, so the
// conversion is defined (found by fuzz/fuzz_gcode.cpp).
constexpr int kMaxCount = 1000000;
// Canned-cycle L repeats: each is a few canonical calls.
constexpr int kMaxRepeats = 10000;

// G codes are handled as value x 10 so that G38.2 is 382 and G59.3 is 593.
constexpr int g(int whole, int tenth = 0) {
  return whole * 10 + tenth;
}

// Modal groups (NIST RS274/NGC numbering).
enum GGroup : int {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedModeGroup = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kRetract = 10,
  kCoordSystem = 12,
  kPathControl = 13,
  kGroupCount = 14
};
enum MGroup : int { kStopping = 0, kToolChange = 1, kSpindle = 2, kCoolant = 3, kMGroupCount = 4 };

const char* group_name(int group) {
  switch (group) {
    case kNonModal:
      return "non-modal (G4 G10 G28 G30 G53 G92)";
    case kMotion:
      return "motion";
    case kPlane:
      return "plane";
    case kDistance:
      return "distance mode";
    case kArcDistance:
      return "arc distance mode";
    case kFeedModeGroup:
      return "feed rate mode";
    case kUnits:
      return "units";
    case kCutterComp:
      return "cutter compensation";
    case kToolLength:
      return "tool length offset";
    case kRetract:
      return "canned cycle return";
    case kCoordSystem:
      return "coordinate system";
    case kPathControl:
      return "path control";
    default:
      return "?";
  }
}

// The group of a supported G code; -1 for codes this dialect refuses.
int g_group(int code) {
  switch (code) {
    case g(4):
    case g(10):
    case g(28):
    case g(28, 1):
    case g(30):
    case g(30, 1):
    case g(53):
    case g(92):
    case g(92, 1):
    case g(92, 2):
    case g(92, 3):
      return kNonModal;
    case g(0):
    case g(1):
    case g(2):
    case g(3):
    case g(38, 2):
    case g(38, 3):
    case g(38, 4):
    case g(38, 5):
    case g(73):
    case g(80):
    case g(81):
    case g(82):
    case g(83):
      return kMotion;
    case g(17):
    case g(18):
    case g(19):
      return kPlane;
    case g(90):
    case g(91):
      return kDistance;
    case g(90, 1):
    case g(91, 1):
      return kArcDistance;
    case g(93):
    case g(94):
      return kFeedModeGroup;
    case g(20):
    case g(21):
      return kUnits;
    case g(40):
      return kCutterComp;
    case g(43, 1):
    case g(49):
      return kToolLength;
    case g(98):
    case g(99):
      return kRetract;
    case g(54):
    case g(55):
    case g(56):
    case g(57):
    case g(58):
    case g(59):
    case g(59, 1):
    case g(59, 2):
    case g(59, 3):
      return kCoordSystem;
    case g(61):
    case g(61, 1):
    case g(64):
      return kPathControl;
    default:
      return -1;
  }
}

// What to say about a G code that is refused.
std::string refused_g(int code) {
  switch (code) {
    case g(41):
    case g(42):
    case g(41, 1):
    case g(42, 1):
      return "cutter radius compensation is not supported: program the tool centre path (G40 is accepted)";
    case g(15):
    case g(16):
      return "polar coordinates are not supported";
    case g(7):
    case g(8):
      return "lathe diameter/radius mode is not supported (this is a mill dialect)";
    case g(33):
    case g(33, 1):
    case g(76):
      return "threading and rigid tapping cycles are not supported";
    case g(70):
    case g(71):
    case g(71, 1):
    case g(71, 2):
    case g(72):
    case g(72, 1):
    case g(72, 2):
    case g(74):
      return "lathe cycles are not supported";
    case g(84):
    case g(85):
    case g(86):
    case g(87):
    case g(88):
    case g(89):
      return "this canned cycle is not supported; the supported ones are G73, G81, G82 and G83";
    case g(43):
    case g(43, 2):
      return "tool table offsets are not supported; use G43.1 Z (dynamic tool length)";
    case g(5):
    case g(5, 1):
    case g(5, 2):
    case g(5, 3):
      return "splines and NURBS are not supported; use G1/G2/G3";
    case g(52):
      return "local offsets (G52) are not supported; use G92 or G10";
    case g(96):
    case g(97):
      return "constant surface speed (G96/G97) is not supported";
    default:
      return "unsupported G code";
  }
}

int m_group(int code) {
  switch (code) {
    case 0:
    case 1:
    case 2:
    case 30:
      return kStopping;
    case 6:
      return kToolChange;
    case 3:
    case 4:
    case 5:
      return kSpindle;
    case 7:
    case 8:
    case 9:
      return kCoolant;
    default:
      return -1;
  }
}

std::string refused_m(int code) {
  if (code == 98 || code == 99) return "subroutine calls (M98/M99) are not supported";
  if (code >= 48 && code <= 53) return "override controls are not supported";
  if (code >= 62 && code <= 68) return "digital/analog I/O M codes are not supported";
  if (code >= 100 && code <= 199) return "user-defined M codes are not supported";
  return "unsupported M code";
}

bool is_cycle(MotionCode m) {
  return m == g(73) || m == g(81) || m == g(82) || m == g(83);
}
bool is_arc(MotionCode m) {
  return m == g(2) || m == g(3);
}
bool is_probe(MotionCode m) {
  return m >= g(38, 2) && m <= g(38, 5);
}

std::string g_text(int code) {
  std::string s = "G" + std::to_string(code / 10);
  if (code % 10 != 0) s += "." + std::to_string(code % 10);
  return s;
}

char axis_letter(int axis) {
  return static_cast<char>('X' + axis);
}
char offset_letter(int axis) {
  return static_cast<char>('I' + axis);
}

// Failure inside a block: carries the error out to execute_line.
struct Failure {
  Error error;
};

}  // namespace

// Executes one parsed block on an Interpreter (a copy: execute_line keeps it
// only when the whole block succeeded).
class BlockExecutor {
 public:
  BlockExecutor(Interpreter& st, const Block& b, int line, std::vector<CanonCall>& out)
      : st_(st), m_(st.modal_), b_(b), line_(line), out_(out) {}

  void run() {
    classify();
    check();
    execute();
  }

 private:
  // ---- errors ----------------------------------------------------------
  [[noreturn]] void fail(const Word* w, int code, const std::string& message) const {
    Error e;
    e.file = st_.file_;
    e.line = line_;
    e.column = w != nullptr ? w->column : 1;
    e.word = w != nullptr ? w->text : "";
    e.grbl_code = code;
    e.message = message;
    throw Failure{e};
  }
  [[noreturn]] void fail(char letter, int code, const std::string& message) const {
    fail(word(letter), code, message);
  }
  const Word* word(char letter) const { return b_.has(letter) ? &*b_.word(letter) : nullptr; }
  bool has(char letter) const { return b_.has(letter); }
  double value(char letter) const { return b_.value(letter); }

  // ---- classification ----------------------------------------------------
  void classify() {
    for (const Word& w : b_.g) {
      // The range first: std::lround of a value beyond long is unspecified.
      if (w.value < 0 || w.value > 1000) fail(&w, grbl::unsupported_command, "unsupported G code");
      const double tenths = w.value * 10.0;
      const long code = std::lround(tenths);
      if (std::fabs(tenths - static_cast<double>(code)) > 1e-6)
        fail(&w, grbl::unsupported_command, "unsupported G code");
      const int c = static_cast<int>(code);
      const int group = g_group(c);
      if (group < 0) fail(&w, grbl::unsupported_command, refused_g(c));
      if (g_word_[group] != nullptr)
        fail(&w, grbl::modal_group_violation,
             g_word_[group]->text + " and " + w.text + " are both in the " + group_name(group) +
                 " modal group: one per line");
      g_word_[group] = &w;
      g_code_[group] = c;
    }
    for (const Word& w : b_.m) {
      if (w.value < 0 || w.value != std::floor(w.value))
        fail(&w, grbl::command_value_not_integer, "an M code is a whole number");
      // Beyond every M code, and beyond what an int holds (the conversion would be undefined).
      if (w.value > 1000) fail(&w, grbl::unsupported_command, "unsupported M code");
      const int c = static_cast<int>(w.value);
      const int group = m_group(c);
      if (group < 0) fail(&w, grbl::unsupported_command, refused_m(c));
      if (m_word_[group] != nullptr)
        fail(&w, grbl::modal_group_violation,
             m_word_[group]->text + " and " + w.text + " are in the same modal group: one per line");
      m_word_[group] = &w;
      m_code_[group] = c;
    }
    axis_words_ = has('X') || has('Y') || has('Z');
    const int nm = gc(kNonModal);
    g0_uses_axes_ = nm == g(10) || nm == g(28) || nm == g(30) || nm == g(92) || gc(kToolLength) == g(43, 1);
    if (gc(kMotion) >= 0) {
      motion_ = gc(kMotion);
    } else if (axis_words_ && !g0_uses_axes_) {
      motion_ = m_.motion;
    }
  }
  int gc(int group) const { return g_code_.at(static_cast<size_t>(group)); }
  int mc(int group) const { return m_code_.at(static_cast<size_t>(group)); }

  // ---- checks that need no state change (LinuxCNC's check_items) ---------
  void check() {
    const int nm = gc(kNonModal);
    const Word* axis_user = gc(kToolLength) == g(43, 1) ? g_word_[kToolLength] : g_word_[kNonModal];
    if (g0_uses_axes_ && gc(kMotion) >= 0 && gc(kMotion) != g(80) && axis_words_)
      fail(g_word_[kMotion], grbl::axis_command_conflict,
           "both " + axis_user->text + " and " + g_word_[kMotion]->text +
               " use the axis words; put them on separate lines");
    if (axis_words_ && !g0_uses_axes_ && (motion_ < 0 || motion_ == g(80))) {
      const char a = has('X') ? 'X' : has('Y') ? 'Y' : 'Z';
      fail(a, grbl::axis_words_exist,
           motion_ == g(80) ? "axis words with G80 (motion off): nothing would use them"
                            : "axis words without a G code that uses them");
    }
    if (nm == g(53)) {
      if (motion_ != g(0) && motion_ != g(1))
        fail(g_word_[kNonModal], grbl::g53_invalid_motion_mode, "G53 moves need G0 or G1");
      if (distance() == Distance::incremental)
        fail(g_word_[kNonModal], grbl::g53_invalid_motion_mode,
             "G53 takes absolute machine coordinates: not with G91");
    }
    check_unused_words();
    if (has('F') && value('F') < 0) fail('F', grbl::negative_value, "the feed rate must not be negative");
    if (has('S') && value('S') < 0) fail('S', grbl::negative_value, "the spindle speed must not be negative");
    if (has('T') && (value('T') < 0 || value('T') != std::floor(value('T'))))
      fail('T', grbl::command_value_not_integer, "a tool number is a whole number >= 0");
    if (has('L') && (value('L') != std::floor(value('L'))))
      fail('L', grbl::command_value_not_integer, "L takes a whole number");
  }

  Plane plane() const {
    switch (gc(kPlane)) {
      case g(17):
        return Plane::xy;
      case g(18):
        return Plane::xz;
      case g(19):
        return Plane::yz;
      default:
        return m_.plane;
    }
  }
  Distance distance() const {
    if (gc(kDistance) == g(90)) return Distance::absolute;
    if (gc(kDistance) == g(91)) return Distance::incremental;
    return m_.distance;
  }
  Distance arc_distance() const {
    if (gc(kArcDistance) == g(90, 1)) return Distance::absolute;
    if (gc(kArcDistance) == g(91, 1)) return Distance::incremental;
    return m_.arc_distance;
  }
  // mm per program unit for this block (G20/G21 take effect before F is read,
  // as in Grbl: "G20 F10" is 10 inch/min).
  double scale() const {
    if (gc(kUnits) == g(20)) return kMmPerInch;
    if (gc(kUnits) == g(21)) return 1.0;
    return m_.units == Units::inch ? kMmPerInch : 1.0;
  }

  void check_unused_words() {
    const int nm = gc(kNonModal);
    const bool arc = is_arc(motion_);
    const bool cycle = is_cycle(motion_);
    for (const char c : {'I', 'J', 'K'}) {
      if (!has(c)) continue;
      if (!arc) fail(c, grbl::unused_words, std::string(1, c) + " word with no G2/G3 arc to use it");
      const PlaneAxes ax = plane_axes(plane());
      if (c != offset_letter(ax.first) && c != offset_letter(ax.second))
        fail(c, grbl::unused_words,
             std::string(1, c) + " word for an arc in the " +
                 (plane() == Plane::xy   ? "XY (G17)"
                  : plane() == Plane::xz ? "XZ (G18)"
                                         : "YZ (G19)") +
                 " plane: give the offsets of the plane's two axes");
    }
    if (has('R')) {
      if (nm == g(10))
        fail('R', grbl::unsupported_command, "G10 R (coordinate system rotation) is not supported");
      if (!arc && !cycle) fail('R', grbl::unused_words, "R word with no G2/G3 or canned cycle to use it");
    }
    if (has('P') && nm != g(4) && nm != g(10) && gc(kPathControl) != g(64) && !arc && motion_ != g(82))
      fail('P', grbl::unused_words, "P word with no G4, G10, G64, G2/G3 or G82 to use it");
    if (has('Q')) {
      if (gc(kPathControl) == g(64) && motion_ != g(73) && motion_ != g(83))
        fail('Q', grbl::unsupported_command, "G64 Q (naive CAM tolerance) is not supported; G64 P is");
      if (motion_ != g(73) && motion_ != g(83))
        fail('Q', grbl::unused_words, "Q word with no G73/G83 peck cycle to use it");
    }
    if (has('L') && nm != g(10) && !cycle)
      fail('L', grbl::unused_words, "L word with no G10 or canned cycle to use it");
  }

  // ---- coordinates -------------------------------------------------------
  Vec3 offset() const {
    Vec3 o = st_.data_.coord_offsets.at(static_cast<size_t>(m_.coord_system));
    if (st_.data_.g92_applied)
      for (int a = 0; a < 3; ++a) o.at(a) += st_.data_.g92.at(a);
    o[2] += m_.tool_length_mm;
    return o;
  }
  // Current position in program coordinates and units.
  Vec3 program_position() const {
    const Vec3 o = offset();
    const double s = scale();
    Vec3 p{};
    for (int a = 0; a < 3; ++a) p.at(a) = (st_.position_.at(a) - o.at(a)) / s;
    return p;
  }
  Vec3 to_machine(const Vec3& program) const {
    const Vec3 o = offset();
    const double s = scale();
    Vec3 m{};
    for (int a = 0; a < 3; ++a) m.at(a) = program.at(a) * s + o.at(a);
    return m;
  }
  // The end point the axis words name (machine mm); G53 makes them machine
  // coordinates, G91 increments.
  Vec3 target() const {
    Vec3 t = st_.position_;
    const Vec3 o = offset();
    const double s = scale();
    const bool machine = gc(kNonModal) == g(53);
    for (int a = 0; a < 3; ++a) {
      if (!has(axis_letter(a))) continue;
      const double v = value(axis_letter(a)) * s;
      if (machine)
        t.at(a) = v;
      else if (distance() == Distance::absolute)
        t.at(a) = v + o.at(a);
      else
        t.at(a) = st_.position_.at(a) + v;
    }
    return t;
  }

  void emit(const CanonOp& op) { out_.push_back(CanonCall{line_, op}); }
  void traverse(const Vec3& end) {
    emit(StraightTraverse{end});
    st_.position_ = end;
  }
  void feed_to(const Vec3& end, double feed) {
    emit(StraightFeed{end, feed});
    st_.position_ = end;
  }

  // ---- execution in the order of the NIST table -------------------------
  void execute() {
    set_feed_mode();  // 2 G93/G94
    set_feed_rate();  // 3 F
    if (has('S')) {   // 4 S
      m_.spindle_rpm = value('S');
      emit(SetSpindleSpeed{m_.spindle_rpm});
    }
    if (has('T')) {  // 5 T
      const double t = value('T');
      if (t < 0) fail('T', grbl::negative_value, "T (the tool number) must be 0 or more");
      if (t != std::floor(t) || t > kMaxCount)
        fail('T', grbl::command_value_not_integer, "T takes a whole number 0.." + std::to_string(kMaxCount));
      m_.selected_tool = static_cast<int>(t);
      emit(SelectTool{m_.selected_tool});
    }
    if (mc(kToolChange) == 6) {  // 6 M6
      emit(ChangeTool{m_.selected_tool});
      m_.tool = m_.selected_tool;
      m_.spindle = SpindleState::off;
    }
    set_spindle();                                                                  // 7 M3/M4/M5
    set_coolant();                                                                  // 8 M7/M8/M9
    if (gc(kNonModal) == g(4)) dwell();                                             // 10 G4
    m_.plane = plane();                                                             // 11 G17/G18/G19
    if (gc(kUnits) >= 0) m_.units = gc(kUnits) == g(20) ? Units::inch : Units::mm;  // 12
    // 13 G40: cutter compensation is never on.
    set_tool_length();         // 14 G43.1/G49
    set_coord_system();        // 15 G54..G59.3
    set_path_mode();           // 16 G61/G61.1/G64
    m_.distance = distance();  // 17 G90/G91
    m_.arc_distance = arc_distance();
    if (gc(kRetract) >= 0)
      m_.retract = gc(kRetract) == g(99) ? RetractMode::r_plane : RetractMode::initial_level;
    non_modal();  // 19 G28 G30 G10 G92
    motion();     // 20
    stop();       // 21 M0 M1 M2 M30
  }

  void set_feed_mode() {
    if (gc(kFeedModeGroup) < 0) return;
    const FeedMode mode = gc(kFeedModeGroup) == g(93) ? FeedMode::inverse_time : FeedMode::units_per_minute;
    if (mode != m_.feed_mode) {
      // A feed rate of one mode means nothing in the other (LinuxCNC, Grbl).
      m_.feed = 0.0;
      m_.feed_mode = mode;
      emit(SetFeedMode{mode});
    }
  }
  void set_feed_rate() {
    if (!has('F')) return;
    m_.feed = m_.feed_mode == FeedMode::inverse_time ? value('F') : value('F') * scale();
  }
  void set_spindle() {
    switch (mc(kSpindle)) {
      case 3:
      case 4:
        m_.spindle = mc(kSpindle) == 3 ? SpindleState::clockwise : SpindleState::counterclockwise;
        emit(StartSpindle{mc(kSpindle) == 3, m_.spindle_rpm});
        break;
      case 5:
        m_.spindle = SpindleState::off;
        emit(StopSpindle{});
        break;
      default:
        break;
    }
  }
  void set_coolant() {
    switch (mc(kCoolant)) {
      case 7:
        m_.mist = true;
        break;
      case 8:
        m_.flood = true;
        break;
      case 9:
        m_.mist = false;
        m_.flood = false;
        break;
      default:
        return;
    }
    emit(SetCoolant{m_.mist, m_.flood});
  }
  void dwell() {
    if (!has('P'))
      fail(g_word_[kNonModal], grbl::value_word_missing, "G4 needs P, the dwell time in seconds");
    if (value('P') < 0) fail('P', grbl::negative_value, "the dwell time must not be negative");
    emit(Dwell{value('P')});
  }
  void set_tool_length() {
    if (gc(kToolLength) == g(49)) {
      m_.tool_length_mm = 0.0;
    } else if (gc(kToolLength) == g(43, 1)) {
      if (has('X') || has('Y'))
        fail(has('X') ? 'X' : 'Y', grbl::g43_dynamic_axis_error, "G43.1 takes the tool length on Z only");
      if (!has('Z'))
        fail(g_word_[kToolLength], grbl::g43_dynamic_axis_error, "G43.1 needs Z, the tool length");
      m_.tool_length_mm = value('Z') * scale();
    }
  }
  void set_coord_system() {
    const int c = gc(kCoordSystem);
    if (c < 0) return;
    m_.coord_system = c < g(59, 1) ? (c - g(54)) / 10 : 6 + (c - g(59, 1));
  }
  void set_path_mode() {
    const int c = gc(kPathControl);
    if (c < 0) return;
    double tolerance = 0.0;
    if (c == g(64) && has('P')) {
      if (value('P') < 0) fail('P', grbl::negative_value, "the G64 path tolerance must not be negative");
      tolerance = value('P') * scale();
    }
    m_.path_mode = c == g(61)      ? PathMode::exact_path
                   : c == g(61, 1) ? PathMode::exact_stop
                                   : PathMode::continuous;
    m_.path_tolerance_mm = tolerance;
    emit(SetPathMode{m_.path_mode, tolerance});
  }

  // ---- step 19 -----------------------------------------------------------
  void non_modal() {
    const int c = gc(kNonModal);
    const Word* w = g_word_[kNonModal];
    if (c == g(28) || c == g(30)) {
      go_home(c == g(28) ? st_.data_.g28 : st_.data_.g30);
    } else if (c == g(28, 1) || c == g(30, 1)) {
      // Axis words on this line belong to the motion mode (step 20).
      (c == g(28, 1) ? st_.data_.g28 : st_.data_.g30) = st_.position_;
    } else if (c == g(10)) {
      set_coord_data();
    } else if (c == g(92)) {
      if (!axis_words_) fail(w, grbl::no_axis_words, "G92 needs at least one axis word");
      PersistentData& d = st_.data_;
      const Vec3 cs = d.coord_offsets.at(static_cast<size_t>(m_.coord_system));
      for (int a = 0; a < 3; ++a) {
        const double tlo = a == 2 ? m_.tool_length_mm : 0.0;
        if (has(axis_letter(a)))
          d.g92.at(a) = st_.position_.at(a) - cs.at(a) - tlo - value(axis_letter(a)) * scale();
        else if (!d.g92_applied)
          d.g92.at(a) = 0.0;  // LinuxCNC: an axis not named keeps the offset in effect
      }
      d.g92_applied = true;
    } else if (c == g(92, 1)) {
      st_.data_.g92 = Vec3{};
      st_.data_.g92_applied = true;
    } else if (c == g(92, 2) || c == g(92, 3)) {
      st_.data_.g92_applied = c == g(92, 3);
    }
  }

  // G28/G30: with axis words, a rapid to that intermediate point (program
  // coordinates) and then only the named axes to the stored position; without,
  // every axis (after a null rapid to where it is, as LinuxCNC emits it).
  void go_home(const Vec3& stored) {
    const Vec3 via = target();
    traverse(via);
    Vec3 end = via;
    for (int a = 0; a < 3; ++a)
      if (!axis_words_ || has(axis_letter(a))) end.at(a) = stored.at(a);
    traverse(end);
  }

  void set_coord_data() {
    const Word* w = g_word_[kNonModal];
    if (!has('L'))
      fail(w, grbl::value_word_missing, "G10 needs L2 (set offsets) or L20 (set current position)");
    const double l = value('L');
    if (l != 2 && l != 20)
      fail('L', grbl::unsupported_command, "only G10 L2 and G10 L20 are supported (no tool table)");
    if (!has('P'))
      fail(w, grbl::value_word_missing, "G10 needs P, the coordinate system 1..9 (0: the current one)");
    const double p = value('P');
    if (p != std::floor(p)) fail('P', grbl::command_value_not_integer, "G10 P takes a whole number 0..9");
    if (p < 0 || p > 9)
      fail('P', grbl::unsupported_coord_sys, "G10 P must be 0..9 (1 = G54 ... 9 = G59.3, 0 = current)");
    const int system = p == 0 ? m_.coord_system : static_cast<int>(p) - 1;
    Vec3& cs = st_.data_.coord_offsets.at(static_cast<size_t>(system));
    for (int a = 0; a < 3; ++a) {
      if (!has(axis_letter(a))) continue;
      const double v = value(axis_letter(a)) * scale();
      if (l == 2) {
        cs.at(a) = v;
      } else {
        const double g92 = st_.data_.g92_applied ? st_.data_.g92.at(a) : 0.0;
        const double tlo = a == 2 ? m_.tool_length_mm : 0.0;
        cs.at(a) = st_.position_.at(a) - g92 - tlo - v;
      }
    }
  }

  // ---- step 20 -----------------------------------------------------------
  void motion() {
    if (motion_ < 0) return;
    if (motion_ == g(80)) {
      m_.motion = motion_;
    } else if (motion_ == g(0)) {
      traverse(target());
    } else if (motion_ == g(1)) {
      const Vec3 end = target();
      feed_to(end, feed_for(std::hypot(end[0] - st_.position_[0], end[1] - st_.position_[1],
                                       end[2] - st_.position_[2])));
    } else if (is_arc(motion_)) {
      arc();
    } else if (is_probe(motion_)) {
      probe();
    } else {
      cycle();
    }
    // G53 is not modal; a G0/G1 with it stays the motion mode.
    m_.motion = motion_;
    if (!is_cycle(motion_)) st_.cycle_initial_set_ = false;
  }

  // The feed for a move of `length` mm; checks that there is one.
  double feed_for(double length) {
    const Word* mw = g_word_[kMotion];
    if (m_.feed_mode == FeedMode::inverse_time) {
      if (!has('F'))
        fail(mw, grbl::undefined_feed_rate, "in G93 inverse time every G1/G2/G3 line needs its own F");
      if (m_.feed <= 0) fail('F', grbl::undefined_feed_rate, "the inverse time F must be > 0");
      return m_.feed * length;
    }
    if (m_.feed <= 0)
      fail(mw, grbl::undefined_feed_rate, "no feed rate: give F (units per minute) before or on this line");
    return m_.feed;
  }

  void arc() {
    const Word* mw = g_word_[kMotion];
    const PlaneAxes ax = plane_axes(m_.plane);
    const Vec3 start = st_.position_;
    const Vec3 end = target();
    const double s = scale();
    const bool inch = m_.units == Units::inch;
    const char i1 = offset_letter(ax.first);
    const char i2 = offset_letter(ax.second);
    int turns = 1;
    if (has('P')) {
      if (value('P') != std::floor(value('P')) || value('P') < 1 || value('P') > kMaxCount)
        fail('P', grbl::command_value_not_integer,
             "arc P (turns) takes a whole number 1.." + std::to_string(kMaxCount));
      turns = static_cast<int>(value('P'));
    }
    const bool cw = motion_ == g(2);
    Vec3 centre = start;
    if (has('R')) {
      if (has(i1) || has(i2)) fail('R', grbl::unused_words, "give either R or the centre offsets, not both");
      const double radius = value('R') * s;
      const double s1 = start[ax.first];
      const double s2 = start[ax.second];
      const double e1 = end[ax.first];
      const double e2 = end[ax.second];
      if (e1 == s1 && e2 == s2)
        fail('R', grbl::invalid_target,
             "an R arc cannot end where it starts (the centre is undefined); use I/J/K for a full circle");
      const double abs_r = std::fabs(radius);
      const double mid1 = (e1 + s1) / 2.0;
      const double mid2 = (e2 + s2) / 2.0;
      double half = std::hypot(mid1 - e1, mid2 - e2);
      // LinuxCNC's RADIUS_TOLERANCE: 0.00005 inch.
      if (half - abs_r > 0.00005 * kMmPerInch)
        fail('R', grbl::arc_radius_error, "the radius is too small to reach the end point");
      if (half / abs_r > 1.0 - 1e-12) half = abs_r;
      const double chord = std::atan2(e2 - s2, e1 - s1);
      const double theta = (cw == (radius > 0)) ? chord - M_PI_2 : chord + M_PI_2;
      const double off = abs_r * std::cos(std::asin(half / abs_r));
      centre[ax.first] = mid1 + off * std::cos(theta);
      centre[ax.second] = mid2 + off * std::sin(theta);
    } else {
      if (!has(i1) && !has(i2))
        fail(mw, grbl::no_offsets_in_plane,
             std::string("an arc needs R or the centre offsets ") + i1 + "/" + i2 + " of the selected plane");
      const Vec3 o = offset();
      for (const auto& [axis, letter] : {std::pair<int, char>{ax.first, i1}, {ax.second, i2}}) {
        if (arc_distance() == Distance::absolute) {
          if (!has(letter))
            fail(mw, grbl::no_offsets_in_plane,
                 std::string("an absolute-centre (G90.1) arc needs both ") + i1 + " and " + i2);
          centre.at(axis) = value(letter) * s + o.at(axis);
        } else {
          centre.at(axis) = start.at(axis) + (has(letter) ? value(letter) * s : 0.0);
        }
      }
      const double r1 = std::hypot(start[ax.first] - centre[ax.first], start[ax.second] - centre[ax.second]);
      const double r2 = std::hypot(end[ax.first] - centre[ax.first], end[ax.second] - centre[ax.second]);
      // LinuxCNC's tolerances: a zero radius below 0.00005 inch; a spiral
      // allowed up to 0.002*sqrt2 inch (0.02*sqrt2 mm) or 0.1 % of the radius.
      if (r1 < 0.00005 * kMmPerInch || r2 < 0.00005 * kMmPerInch)
        fail(mw, grbl::arc_radius_error, "zero radius arc: the centre is at the start or the end point");
      const double spiral = inch ? 0.002 * M_SQRT2 * kMmPerInch : 0.02 * M_SQRT2;
      const double abs_err = std::fabs(r1 - r2);
      const double rel_err = abs_err / std::max(r1, r2);
      if (abs_err > spiral * 100.0 || (rel_err > 0.001 && abs_err > spiral)) {
        std::ostringstream msg;
        msg << "the radius to the end (" << r2 / s << ") differs from the radius to the start (" << r1 / s
            << "): check the end point and the centre offsets";
        fail(mw, grbl::arc_radius_error, msg.str());
      }
    }
    ArcFeed a{end, centre, m_.plane, cw, turns, 0.0};
    a.feed_mm_min = feed_for(arc_length(start, a));
    emit(a);
    st_.position_ = end;
  }

  void probe() {
    const Word* mw = g_word_[kMotion];
    if (m_.feed_mode == FeedMode::inverse_time)
      fail(mw, grbl::unsupported_command, "probing (G38.x) needs G94 units-per-minute feed, not G93");
    if (m_.feed <= 0) fail(mw, grbl::undefined_feed_rate, "no feed rate for the probe move: give F");
    const Vec3 end = target();
    const Vec3& p = st_.position_;
    // LinuxCNC: the probe point must be more than 0.0001 program units away.
    const double close = 0.0001 * scale();
    if (std::fabs(end[0] - p[0]) < close && std::fabs(end[1] - p[1]) < close &&
        std::fabs(end[2] - p[2]) < close)
      fail(mw, grbl::invalid_target, "the probe target is the current position");
    const ProbeMode mode = static_cast<ProbeMode>(motion_ - g(38, 2));
    emit(StraightProbe{end, mode, m_.feed});
    st_.position_ = end;
  }

  // G73/G81/G82/G83 as LinuxCNC's convert_cycle_xy/_zx/_yz: in program
  // coordinates, aa/bb the plane's axes, cc the drilling axis.
  void cycle() {
    const Word* mw = g_word_[kMotion];
    const PlaneAxes ax = plane_axes(m_.plane);
    const char cc_letter = axis_letter(ax.normal);
    const bool same = m_.motion == motion_;
    const std::string name = g_text(motion_);
    if (m_.feed_mode == FeedMode::inverse_time)
      fail(mw, grbl::none, "canned cycles need G94 units-per-minute feed, not G93");
    if (m_.feed <= 0) fail(mw, grbl::undefined_feed_rate, "no feed rate for the canned cycle: give F");
    if (!has('R') && !same)
      fail(mw, grbl::value_word_missing, name + " needs R, the retract plane, when it starts");
    if (!has(cc_letter) && !same)
      fail(mw, grbl::value_word_missing,
           name + " needs " + cc_letter + ", the bottom of the hole, when it starts");
    int repeats = 1;
    if (has('L')) {
      if (value('L') < 1) fail('L', grbl::value_word_missing, "L (repeats) must be at least 1");
      // Each repeat is a few calls: a bound keeps a typo from filling memory.
      if (value('L') > kMaxRepeats)
        fail('L', grbl::invalid_target, "L (repeats) must be at most " + std::to_string(kMaxRepeats));
      repeats = static_cast<int>(value('L'));
    }
    double q = st_.cycle_q_;
    double p = st_.cycle_p_;
    if (motion_ == g(73) || motion_ == g(83)) {
      if (!has('Q') && !same)
        fail(mw, grbl::value_word_missing, name + " needs Q, the peck depth, when it starts");
      if (has('Q')) q = value('Q');
      if (q <= 0) fail(has('Q') ? word('Q') : mw, grbl::negative_value, "the peck depth Q must be > 0");
    }
    if (motion_ == g(82)) {
      if (!has('P') && !same)
        fail(mw, grbl::value_word_missing, "G82 needs P, the dwell at the bottom, when it starts");
      if (has('P')) p = value('P');
      if (p < 0) fail('P', grbl::negative_value, "the dwell time must not be negative");
    }
    const double r_word = has('R') ? value('R') : st_.cycle_r_;
    const double cc_word = has(cc_letter) ? value(cc_letter) : st_.cycle_cc_;
    const Vec3 cur = program_position();
    double current_cc = cur.at(ax.normal);
    // The initial level (G98's return height) is the drilling-axis position
    // when the series of cycles began, not when this block began.
    if (!st_.cycle_initial_set_) {
      st_.cycle_initial_ = current_cc;
      st_.cycle_initial_set_ = true;
    }
    double old_cc = st_.cycle_initial_;
    double aa = cur.at(ax.first);
    double bb = cur.at(ax.second);
    double aa_inc = 0.0;
    double bb_inc = 0.0;
    double r = r_word;
    double cc = cc_word;
    const char a_letter = axis_letter(ax.first);
    const char b_letter = axis_letter(ax.second);
    if (distance() == Distance::absolute) {
      if (has(a_letter)) aa = value(a_letter);
      if (has(b_letter)) bb = value(b_letter);
    } else {
      // G91: X Y step from here, R from the initial level, Z from R.
      aa_inc = has(a_letter) ? value(a_letter) : 0.0;
      bb_inc = has(b_letter) ? value(b_letter) : 0.0;
      r = r_word + old_cc;
      cc = r + cc_word;
    }
    if (r < cc)
      fail(has('R') ? word('R') : mw, grbl::none,
           std::string("the R plane must not be below the bottom ") + cc_letter + " of the " + name +
               " cycle");
    if (motion_ == g(73) || motion_ == g(83)) {
      // Each peck is two or three calls. A Q far below the depth would make
      // millions, and once the depth dwarfs Q, depth -= q stops changing it.
      const double pecks = (r - cc) / q * repeats;
      if (!(pecks <= kMaxRepeats)) {
        char n[32];
        std::snprintf(n, sizeof n, "%.3g", pecks);
        fail(has('Q') ? word('Q') : mw, grbl::invalid_target,
             std::string("the peck depth Q gives ") + n + " pecks for this depth; at most " +
                 std::to_string(kMaxRepeats));
      }
    }
    // Every move's point: plane coordinates and the drilling axis.
    auto point = [&](double a, double b, double c) {
      Vec3 pt{};
      pt.at(ax.first) = a;
      pt.at(ax.second) = b;
      pt.at(ax.normal) = c;
      return to_machine(pt);
    };
    // Program coordinates come back from machine ones through the offsets, so
    // they carry rounding: compare to kSame where LinuxCNC compares exactly.
    constexpr double kSame = 1e-9;
    if (old_cc < r - kSame) {  // below the R plane: first up to it
      traverse(point(cur.at(ax.first), cur.at(ax.second), r));
      old_cc = r;
      current_cc = r;
    }
    const double clear_cc = m_.retract == RetractMode::r_plane ? r : old_cc;
    const double rapid_delta = m_.units == Units::inch ? 0.010 : 0.010 * kMmPerInch;  // G83_RAPID_DELTA
    for (int i = 0; i < repeats; ++i) {
      aa += aa_inc;
      bb += bb_inc;
      // Position at the higher of here and the clearance height, then down to R.
      if (current_cc < clear_cc + kSame) current_cc = clear_cc;
      traverse(point(aa, bb, current_cc));
      if (std::fabs(current_cc - r) > kSame) traverse(point(aa, bb, r));
      if (motion_ == g(73) || motion_ == g(83)) {
        double depth = r - q;
        while (depth > cc) {  // LinuxCNC's loop, with its rounding
          feed_to(point(aa, bb, depth), m_.feed);
          if (motion_ == g(83)) traverse(point(aa, bb, r));  // G83: out of the hole to R
          traverse(point(aa, bb, depth + rapid_delta));      // back down (G73: a short retract)
          depth -= q;
        }
      }
      feed_to(point(aa, bb, cc), m_.feed);
      if (motion_ == g(82)) emit(Dwell{p});
      traverse(point(aa, bb, clear_cc));
      current_cc = clear_cc;
    }
    st_.cycle_cc_ = cc_word;
    st_.cycle_r_ = r_word;
    st_.cycle_q_ = q;
    st_.cycle_p_ = p;
  }

  // ---- step 21 -----------------------------------------------------------
  void stop() {
    const int c = mc(kStopping);
    if (c == 0 || c == 1) {
      emit(ProgramStop{c == 0 ? StopKind::pause : StopKind::optional_pause});
      return;
    }
    if (c != 2 && c != 30) return;
    // M2/M30 as LinuxCNC: G54, G17, G90, G94, G1, spindle and coolant off;
    // the G92 offset and the tool length offset stay.
    if (m_.spindle != SpindleState::off) emit(StopSpindle{});
    if (m_.mist || m_.flood) emit(SetCoolant{false, false});
    if (m_.feed_mode != FeedMode::units_per_minute) emit(SetFeedMode{FeedMode::units_per_minute});
    m_.coord_system = 0;
    m_.plane = Plane::xy;
    m_.distance = Distance::absolute;
    m_.feed_mode = FeedMode::units_per_minute;
    m_.feed = 0.0;
    m_.motion = g(1);
    m_.spindle = SpindleState::off;
    m_.mist = false;
    m_.flood = false;
    emit(ProgramStop{c == 2 ? StopKind::end : StopKind::end_rewind});
    st_.ended_ = true;
  }

  Interpreter& st_;
  ModalState& m_;
  const Block& b_;
  int line_;
  std::vector<CanonCall>& out_;
  std::array<const Word*, kGroupCount> g_word_{};
  std::array<int, kGroupCount> g_code_ = [] {
    std::array<int, kGroupCount> a{};
    a.fill(-1);
    return a;
  }();
  std::array<const Word*, kMGroupCount> m_word_{};
  std::array<int, kMGroupCount> m_code_ = [] {
    std::array<int, kMGroupCount> a{};
    a.fill(-1);
    return a;
  }();
  bool axis_words_ = false;
  bool g0_uses_axes_ = false;
  MotionCode motion_ = -1;  // the motion this block runs, -1 none
};

Interpreter::Interpreter(const Options& options, std::string file_name)
    : options_(options), file_(std::move(file_name)), data_(options.data), position_(options.start) {}

Vec3 Interpreter::work_position() const {
  Vec3 o = data_.coord_offsets.at(static_cast<size_t>(modal_.coord_system));
  const double s = modal_.units == Units::inch ? kMmPerInch : 1.0;
  Vec3 w{};
  for (int a = 0; a < 3; ++a) {
    const double g92 = data_.g92_applied ? data_.g92.at(a) : 0.0;
    const double tlo = a == 2 ? modal_.tool_length_mm : 0.0;
    w.at(a) = (position_.at(a) - o.at(a) - g92 - tlo) / s;
  }
  return w;
}

LineResult Interpreter::execute_line(std::string_view text, int line_no) {
  LineResult result;
  ended_ = false;
  const size_t first = text.find_first_not_of(" \t");
  if (options_.block_delete && first != std::string_view::npos && text[first] == '/') return result;
  ParsedLine parsed = parse_line(text);
  if (parsed.error) {
    parsed.error->file = file_;
    parsed.error->line = line_no;
    result.error = parsed.error;
    return result;
  }
  if (parsed.block.percent) return result;
  Interpreter next = *this;
  try {
    BlockExecutor(next, parsed.block, line_no, result.calls).run();
  } catch (const Failure& f) {
    result.calls.clear();
    result.error = f.error;
    return result;
  }
  *this = std::move(next);
  return result;
}

std::string modal_report(const ModalState& s) {
  auto num = [](double v) {
    std::ostringstream o;
    o.precision(6);
    o << v;
    return o.str();
  };
  std::string out = "[GC:" + g_text(s.motion);
  static const char* const systems[] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
  out += std::string(" ") + systems[std::clamp(s.coord_system, 0, 8)];
  out += s.plane == Plane::xy ? " G17" : s.plane == Plane::xz ? " G18" : " G19";
  out += s.units == Units::mm ? " G21" : " G20";
  out += s.distance == Distance::absolute ? " G90" : " G91";
  out += s.feed_mode == FeedMode::units_per_minute ? " G94" : " G93";
  out += s.spindle == SpindleState::clockwise          ? " M3"
         : s.spindle == SpindleState::counterclockwise ? " M4"
                                                       : " M5";
  if (s.mist) out += " M7";
  if (s.flood) out += " M8";
  if (!s.mist && !s.flood) out += " M9";
  const double feed =
      s.feed_mode == FeedMode::units_per_minute && s.units == Units::inch ? s.feed / kMmPerInch : s.feed;
  out += " T" + std::to_string(s.tool) + " F" + num(feed) + " S" + num(s.spindle_rpm) + "]";
  return out;
}

ProgramResult interpret_program(std::string_view text, const std::string& file_name, const Options& options) {
  ProgramResult result;
  Interpreter interp(options, file_name);
  bool seen_content = false;
  bool percent_open = false;
  size_t pos = 0;
  int line_no = 0;
  while (pos <= text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_no;
    result.lines = line_no;
    const size_t first = line.find_first_not_of(" \t");
    if (first != std::string_view::npos && line[first] == '%') {
      // '%' first opens the program; the next '%' (or one after content) closes it.
      if (!seen_content && !percent_open) {
        percent_open = true;
      } else {
        break;
      }
    } else {
      if (first != std::string_view::npos) seen_content = true;
      LineResult r = interp.execute_line(line, line_no);
      if (r.error) {
        result.errors.push_back(std::move(*r.error));
      } else {
        result.calls.insert(result.calls.end(), r.calls.begin(), r.calls.end());
      }
      if (interp.program_ended()) break;
    }
    if (end == text.size()) break;
    pos = end + 1;
  }
  if (!result.errors.empty()) result.calls.clear();
  return result;
}

ProgramResult interpret_file(const std::string& path, const Options& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    ProgramResult result;
    Error e;
    e.file = path;
    e.message = "cannot read the file";
    result.errors.push_back(e);
    return result;
  }
  std::ostringstream text;
  text << in.rdbuf();
  return interpret_program(text.str(), path, options);
}

}  // namespace mc::gcode
