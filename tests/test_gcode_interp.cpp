// Semantics of the G-code interpreter: units, offsets, arcs, canned cycles,
// reference positions, the order of execution and the line-server API.
#include <gtest/gtest.h>

#include <cmath>

#include "gcode_helpers.hpp"

using namespace gcode_test;

// ---- units and feed -----------------------------------------------------

TEST(GcodeUnits, InchesBecomeMillimetres) {
  const auto c = calls_of("G20 G0 X1 Y-2 Z0.5\nG1 X2 F10\nG21 G1 X0 F100\n");
  const auto e = ends(c);
  ASSERT_EQ(e.size(), 3U);
  EXPECT_TRUE(near3(e[0], {25.4, -50.8, 12.7}));
  EXPECT_TRUE(near3(e[1], {50.8, -50.8, 12.7}));
  const auto feeds = only<StraightFeed>(c);
  EXPECT_DOUBLE_EQ(feeds[0].feed_mm_min, 254.0);  // 10 inch/min
  EXPECT_DOUBLE_EQ(feeds[1].feed_mm_min, 100.0);
}

TEST(GcodeUnits, FOnAG20LineIsInches) {
  // G20 takes effect before F is read (Grbl's order); the feed is kept in mm/min.
  const auto feeds = only<StraightFeed>(calls_of("G20 F10 G1 X1\nG21 G1 X0\n"));
  EXPECT_DOUBLE_EQ(feeds[0].feed_mm_min, 254.0);
  EXPECT_DOUBLE_EQ(feeds[1].feed_mm_min, 254.0);
}

TEST(GcodeUnits, InverseTimeFeedIsTheSpeedThatTakesOneOverFMinutes) {
  const auto c = calls_of("G0 X0 Y0\nG93 G1 X30 Y40 F2\nG2 X30 Y40 I-10 F0.5\nG94 F100 G1 X0\n");
  const auto feeds = only<StraightFeed>(c);
  EXPECT_DOUBLE_EQ(feeds[0].feed_mm_min, 100.0);  // 50 mm in 1/2 minute
  const auto arcs = only<ArcFeed>(c);
  EXPECT_NEAR(arcs[0].feed_mm_min, 2 * M_PI * 10 * 0.5, 1e-9);
  EXPECT_DOUBLE_EQ(feeds[1].feed_mm_min, 100.0);
  EXPECT_EQ(only<SetFeedMode>(c).size(), 2U);
}

// ---- offsets ------------------------------------------------------------

TEST(GcodeOffsets, WorkOffsetsG92AndToolLengthAddUp) {
  const auto c = calls_of(
      "G10 L2 P2 X10 Y20 Z-30\n"
      "G55 G0 X1 Y2 Z3\n"    // 11 22 -27
      "G92 X0 Y0 Z0\n"       // G92 = 1 2 3
      "G0 X1 Y1 Z1\n"        // 12 23 -26
      "G43.1 Z5\n"           //
      "G0 Z0\n"              // z = 0 - 30 + 3 + 5
      "G92.2 G0 X0 Y0 Z0\n"  // suspended: 10 20 -25
      "G92.3 G0 X0 Y0 Z0\n"  // restored: 11 22 -22
      "G49 G92.1 G0 X0 Y0 Z0\n"
      "G54 G0 X0 Y0 Z0\n");
  const auto e = ends(c);
  ASSERT_EQ(e.size(), 7U);
  EXPECT_TRUE(near3(e[0], {11, 22, -27}));
  EXPECT_TRUE(near3(e[1], {12, 23, -26}));
  EXPECT_TRUE(near3(e[2], {12, 23, -22}));
  EXPECT_TRUE(near3(e[3], {10, 20, -25}));
  EXPECT_TRUE(near3(e[4], {11, 22, -22}));
  EXPECT_TRUE(near3(e[5], {10, 20, -30}));
  EXPECT_TRUE(near3(e[6], {0, 0, 0}));
}

TEST(GcodeOffsets, G10L20MakesTheCurrentPointTheGivenCoordinates) {
  Options o;
  o.start = {100, 50, 0};
  Interpreter in(o);
  ASSERT_TRUE(in.execute_line("G10 L20 P1 X0 Y5", 1).ok());
  EXPECT_TRUE(near3(in.data().coord_offsets[0], {100, 45, 0}));
  EXPECT_TRUE(near3(in.work_position(), {0, 5, 0}));
  ASSERT_TRUE(in.execute_line("G20 G10 L20 P3 X1", 2).ok());  // inches, G56 (not active)
  EXPECT_NEAR(in.data().coord_offsets[2][0], 100 - 25.4, 1e-12);
}

TEST(GcodeOffsets, G53IsMachineCoordinatesForOneLine) {
  const auto e = ends(calls_of("G10 L2 P1 X5 Y5 Z5\nG0 X0 Y0 Z0\nG53 G1 X1 F10\nG0 Y0\n"));
  ASSERT_EQ(e.size(), 3U);
  EXPECT_TRUE(near3(e[1], {1, 5, 5}));
  EXPECT_TRUE(near3(e[2], {1, 5, 5}));
}

TEST(GcodeOffsets, StartPositionAndIncrementalMoves) {
  Options o;
  o.start = {10, 20, 30};
  const auto e = ends(calls_of("G91 G0 X1 Y-1\nG1 Z-5 F100\n", o));
  EXPECT_TRUE(near3(e[0], {11, 19, 30}));
  EXPECT_TRUE(near3(e[1], {11, 19, 25}));
}

TEST(GcodeOffsets, PersistentDataIsReadAndRestored) {
  Interpreter a;
  ASSERT_TRUE(a.execute_line("G10 L2 P2 X7", 1).ok());
  ASSERT_TRUE(a.execute_line("G0 X3 Y4 Z5", 2).ok());
  ASSERT_TRUE(a.execute_line("G28.1", 3).ok());
  ASSERT_TRUE(a.execute_line("G92 X0", 4).ok());
  const PersistentData saved = a.data();
  EXPECT_TRUE(near3(saved.g28, {3, 4, 5}));
  EXPECT_TRUE(near3(saved.g92, {3, 0, 0}));

  Options o;
  o.data = saved;
  Interpreter b(o);
  const LineResult r = b.execute_line("G55 G0 X0 Y0 Z0", 1);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(near3(end_of(r.calls.back().op), {10, 0, 0}));
  Interpreter c;
  c.set_data(saved);
  EXPECT_TRUE(near3(end_of(c.execute_line("G28", 1).calls.back().op), {3, 4, 5}));
}

// ---- reference positions ------------------------------------------------

TEST(GcodeHome, G28WithAxesGoesThroughThePointThenOnlyThoseAxes) {
  Options o;
  o.data.g28 = {1, 2, 3};
  o.data.g30 = {-1, -2, -3};
  const auto e = ends(calls_of("G0 X10 Y10 Z10\nG28 Z20\nG30\n", o));
  ASSERT_EQ(e.size(), 5U);
  EXPECT_TRUE(near3(e[1], {10, 10, 20}));
  EXPECT_TRUE(near3(e[2], {10, 10, 3}));
  EXPECT_TRUE(near3(e[3], {10, 10, 3}));  // null rapid, as LinuxCNC
  EXPECT_TRUE(near3(e[4], {-1, -2, -3}));
}

// ---- arcs ---------------------------------------------------------------

TEST(GcodeArcs, RPositiveIsTheShortArcRNegativeTheLong) {
  const auto arcs = only<ArcFeed>(calls_of("F100 G0 X0 Y0\nG2 X10 Y10 R10\nG0 X0 Y0\nG2 X10 Y10 R-10\n"));
  ASSERT_EQ(arcs.size(), 2U);
  EXPECT_TRUE(near3(arcs[0].centre, {10, 0, 0}));
  EXPECT_TRUE(near3(arcs[1].centre, {0, 10, 0}));
  EXPECT_NEAR(arc_sweep({0, 0, 0}, arcs[0]), M_PI / 2, 1e-12);
  EXPECT_NEAR(arc_sweep({0, 0, 0}, arcs[1]), 3 * M_PI / 2, 1e-12);
  EXPECT_TRUE(arcs[0].clockwise);
}

TEST(GcodeArcs, FullCircleTurnsAndHelix) {
  const auto arcs = only<ArcFeed>(calls_of("F100 G0 X5 Y0 Z0\nG3 X5 Y0 Z-2 I-5 J0 P3\n"));
  ASSERT_EQ(arcs.size(), 1U);
  const ArcFeed& a = arcs[0];
  EXPECT_FALSE(a.clockwise);
  EXPECT_EQ(a.turns, 3);
  EXPECT_TRUE(near3(a.centre, {0, 0, 0}));
  EXPECT_TRUE(near3(a.end, {5, 0, -2}));
  EXPECT_NEAR(arc_sweep({5, 0, 0}, a), 6 * M_PI, 1e-12);
  EXPECT_NEAR(arc_length({5, 0, 0}, a), std::hypot(30 * M_PI, 2.0), 1e-9);
}

TEST(GcodeArcs, PlanesUseTheirOwnOffsetsAndAxes) {
  const auto arcs = only<ArcFeed>(calls_of("F100 G18 G2 X10 Z0 I5 K0 Y3\nG19 G3 Y13 Z0 J5\n"));
  ASSERT_EQ(arcs.size(), 2U);
  EXPECT_EQ(arcs[0].plane, Plane::xz);
  EXPECT_TRUE(near3(arcs[0].centre, {5, 0, 0}));
  EXPECT_TRUE(near3(arcs[0].end, {10, 3, 0}));  // Y is the helix axis
  EXPECT_EQ(arcs[1].plane, Plane::yz);
  EXPECT_TRUE(near3(arcs[1].centre, {10, 8, 0}));
  const PlaneAxes xz = plane_axes(Plane::xz);
  EXPECT_EQ(xz.first, 2);  // Z then X, as LinuxCNC
  EXPECT_EQ(xz.normal, 1);
}

TEST(GcodeArcs, AbsoluteCentreIsInWorkCoordinates) {
  const auto arcs = only<ArcFeed>(calls_of("F100 G10 L2 P1 X100\nG0 X10 Y0\nG90.1 G2 X-10 Y0 I0 J0\n"));
  ASSERT_EQ(arcs.size(), 1U);
  EXPECT_TRUE(near3(arcs[0].centre, {100, 0, 0}));
}

TEST(GcodeArcs, SmallSpiralWithinLinuxCncToleranceIsAccepted) {
  // r1 = 10, r2 = 10.02: 0.02 mm is under 0.02*sqrt2 mm.
  EXPECT_TRUE(run("F1 G2 X20.02 I10").ok());
  EXPECT_FALSE(run("F1 G2 X20.03 I10").ok());
  // 0.05 mm on a 100 mm radius is under 0.1 %.
  EXPECT_TRUE(run("F1 G2 X200.05 I100").ok());
}

// ---- canned cycles -------------------------------------------------------

// The (z) of every motion of a program that only moves Z in the cycles.
std::vector<double> zs(const std::vector<CanonCall>& calls) {
  std::vector<double> out;
  for (const Vec3& e : ends(calls)) out.push_back(e[2]);
  return out;
}

TEST(GcodeCycles, G81G98ReturnsToTheInitialLevelG99ToR) {
  const auto c = calls_of("F100 G0 X0 Y0 Z10\nG98 G81 X1 Z-2 R2\nG99 X2\n");
  const std::vector<double> want = {10, 10, 2, -2, 10, 10, 2, -2, 2};
  EXPECT_EQ(zs(c), want);
  const auto m = motions(c);
  EXPECT_TRUE(std::holds_alternative<StraightFeed>(m[3]));
  EXPECT_TRUE(std::holds_alternative<StraightTraverse>(m[4]));
}

TEST(GcodeCycles, G83PecksRetractToROnG73OnlyALittle) {
  const auto c83 = calls_of("F100 G0 Z5\nG99 G83 X0 Z-2.5 R1 Q1\n");
  const std::vector<double> w83 = {5, 5, 1, 0, 1, 0.254, -1, 1, -0.746, -2, 1, -1.746, -2.5, 1};
  const auto z83 = zs(c83);
  ASSERT_EQ(z83.size(), w83.size());
  for (size_t i = 0; i < w83.size(); ++i) EXPECT_NEAR(z83[i], w83[i], 1e-12) << i;
  const auto c73 = calls_of("F100 G0 Z5\nG99 G73 X0 Z-1.5 R1 Q1\n");
  const std::vector<double> w73 = {5, 5, 1, 0, 0.254, -1, -0.746, -1.5, 1};
  const auto z73 = zs(c73);
  ASSERT_EQ(z73.size(), w73.size());
  for (size_t i = 0; i < w73.size(); ++i) EXPECT_NEAR(z73[i], w73[i], 1e-12) << i;
  // In inches the retract is 0.010 inch.
  const auto ci = calls_of("G20 F10 G0 Z1\nG99 G73 X0 Z-0.2 R0.1 Q0.2\n");
  EXPECT_NEAR(zs(ci)[4], (-0.1 + 0.01) * 25.4, 1e-9);
}

TEST(GcodeCycles, G82DwellsAtTheBottomAndLRepeats) {
  const auto c = calls_of("F100 G0 Z5\nG98 G82 X3 Z-1 R1 P0.75 L2\n");
  const auto dwells = only<Dwell>(c);
  ASSERT_EQ(dwells.size(), 2U);
  EXPECT_DOUBLE_EQ(dwells[0].seconds, 0.75);
  const std::vector<double> want = {5, 5, 1, -1, 5, 5, 1, -1, 5};
  EXPECT_EQ(zs(c), want);
}

TEST(GcodeCycles, IncrementalCyclesStepFromHereAndMeasureZFromR) {
  const auto c = calls_of("F100 G0 X0 Y0 Z8\nG91 G99 G81 X10 Y5 Z-6 R-5 L3\n");
  const auto e = ends(c);
  ASSERT_EQ(e.size(), 1U + 4U + 3U + 3U);
  EXPECT_TRUE(near3(e[1], {10, 5, 8}));
  EXPECT_TRUE(near3(e[2], {10, 5, 3}));
  EXPECT_TRUE(near3(e[3], {10, 5, -3}));
  EXPECT_TRUE(near3(e.back(), {30, 15, 3}));
}

TEST(GcodeCycles, ModalRepeatsInheritRZQAndAG80EndsTheSeries) {
  const auto c = calls_of("F100 G0 Z10\nG98 G83 X1 Z-1 R1 Q5\nX2\nG80\nG0 Z3\nG98 G81 X3 Z-1 R1\nX4\n");
  const auto e = ends(c);
  // The second series starts at Z3, so it returns there, not to 10.
  EXPECT_DOUBLE_EQ(e.back()[2], 3.0);
  EXPECT_EQ(error_of("F1 G81 X1 Z-1 R1\nG80\nX2\n").grbl_code, grbl::axis_words_exist);
}

TEST(GcodeCycles, FollowTheToolAndWorkOffsets) {
  const auto e = ends(calls_of("F100 G10 L2 P1 Z-50\nG43.1 Z10\nG0 X0 Y0 Z5\nG99 G81 X1 Z-1 R1\n"));
  EXPECT_DOUBLE_EQ(e.back()[2], 1 - 50 + 10);
}

// ---- order of execution and modal state --------------------------------

TEST(GcodeOrder, CallsFollowTheNistOrderWithinALine) {
  const auto c = calls_of("F100 G1 X1 G4 P2 M3 S500 T2 M6 M8 M0\n");
  ASSERT_EQ(c.size(), 8U);
  EXPECT_TRUE(std::holds_alternative<SetSpindleSpeed>(c[0].op));
  EXPECT_TRUE(std::holds_alternative<SelectTool>(c[1].op));
  EXPECT_TRUE(std::holds_alternative<ChangeTool>(c[2].op));
  EXPECT_TRUE(std::holds_alternative<StartSpindle>(c[3].op));
  EXPECT_TRUE(std::holds_alternative<SetCoolant>(c[4].op));
  EXPECT_TRUE(std::holds_alternative<Dwell>(c[5].op));
  EXPECT_TRUE(std::holds_alternative<StraightFeed>(c[6].op));
  ASSERT_TRUE(std::holds_alternative<ProgramStop>(c[7].op));
  EXPECT_EQ(std::get<ProgramStop>(c[7].op).kind, StopKind::pause);
  for (const CanonCall& call : c) EXPECT_EQ(call.line, 1);
}

TEST(GcodeOrder, ProbeModesAndPathModes) {
  const auto c = calls_of("F50 G38.2 Z-1\nG0 Z0\nG38.5 Z1\nG64 P0.05\nG61.1\n");
  const auto probes = only<StraightProbe>(c);
  ASSERT_EQ(probes.size(), 2U);
  EXPECT_EQ(probes[0].mode, ProbeMode::toward_error);
  EXPECT_EQ(probes[1].mode, ProbeMode::away);
  EXPECT_DOUBLE_EQ(probes[0].feed_mm_min, 50);
  const auto paths = only<SetPathMode>(c);
  ASSERT_EQ(paths.size(), 2U);
  EXPECT_EQ(paths[0].mode, PathMode::continuous);
  EXPECT_DOUBLE_EQ(paths[0].tolerance_mm, 0.05);
  EXPECT_EQ(paths[1].mode, PathMode::exact_stop);
}

TEST(GcodeModal, ReportReadsLikeGrblsDollarG) {
  Interpreter in;
  EXPECT_EQ(modal_report(in.modal()), "[GC:G80 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]");
  ASSERT_TRUE(in.execute_line("G0 G56 G18 G20 G91 M4 S1200 M7 T3 F12.5", 1).ok());
  ASSERT_TRUE(in.execute_line("M8", 2).ok());
  EXPECT_EQ(modal_report(in.modal()), "[GC:G0 G56 G18 G20 G91 G94 M4 M7 M8 T0 F12.5 S1200]");
  ASSERT_TRUE(in.execute_line("M6 G59.2 G81 X0 Y-1 R0 G90", 3).ok());
  EXPECT_EQ(modal_report(in.modal()), "[GC:G81 G59.2 G18 G20 G90 G94 M5 M7 M8 T3 F12.5 S1200]");
}

TEST(GcodeModal, StartsInG80AsLinuxCncSoAxisWordsNeedAMotion) {
  Interpreter in;
  EXPECT_EQ(in.execute_line("X1", 1).error->grbl_code, grbl::axis_words_exist);
  // Axis words next to a non-modal code that takes none go to the motion mode.
  ASSERT_TRUE(in.execute_line("G0 X1", 2).ok());
  const LineResult r = in.execute_line("G28.1 X2", 3);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(near3(in.data().g28, {1, 0, 0}));
  EXPECT_TRUE(near3(in.machine_position(), {2, 0, 0}));
}

TEST(GcodeModal, AFailedLineChangesNothing) {
  Interpreter in;
  ASSERT_TRUE(in.execute_line("G0 X1", 1).ok());
  const LineResult bad = in.execute_line("G20 G55 G0 X2 G1", 2);
  EXPECT_FALSE(bad.ok());
  EXPECT_TRUE(bad.calls.empty());
  EXPECT_EQ(bad.error->line, 2);
  EXPECT_EQ(in.modal().units, Units::mm);
  EXPECT_EQ(in.modal().coord_system, 0);
  EXPECT_TRUE(near3(in.machine_position(), {1, 0, 0}));
  // Errors raised late in the line (the arc) undo the earlier steps too.
  EXPECT_FALSE(in.execute_line("G20 M3 F10 G2 X5 I1", 3).ok());
  EXPECT_EQ(in.modal().units, Units::mm);
  EXPECT_EQ(in.modal().spindle, SpindleState::off);
}

// Found by fuzz/fuzz_gcode.cpp: a whole-number word beyond what an int holds
// was converted anyway (undefined behaviour). Each is refused, with its word,
// and changes nothing; in range, the same words work.
TEST(GcodeModal, HugeWholeNumberWordsAreRefused) {
  Interpreter in;
  ASSERT_TRUE(in.execute_line("G0 X1 F100", 1).ok());
  const std::string before = modal_report(in.modal());
  const char* const bad[] = {"M22222222222222222222222", "G2222222222222222222222.5", "T99999999999999",
                             "T-1", "T1.5", "G17 G2 X1 I1 P99999999999", "G81 X0 Z-1 R1 L99999999999",
                             // Pecks: millions of calls, or a loop where depth -= Q no longer moves.
                             "G83 X0 Z-1 R1 Q0.00000001", "G73 X0 Z0 R100000000000000000000 Q1"};
  for (const char* line : bad) {
    const LineResult r = in.execute_line(line, 2);
    ASSERT_FALSE(r.ok()) << line;
    EXPECT_TRUE(r.calls.empty()) << line;
    const char letter = line[std::string(line).find_last_of("MGTPLQ")];
    EXPECT_EQ(r.error->word.substr(0, 1), std::string(1, letter)) << line << ": " << r.error->format();
    EXPECT_EQ(modal_report(in.modal()), before) << line;
  }
  EXPECT_TRUE(in.execute_line("T7 M6", 3).ok());
  EXPECT_EQ(in.modal().tool, 7);
  EXPECT_TRUE(in.execute_line("G17 G2 X1 I0.5 P3", 4).ok());
  EXPECT_TRUE(in.execute_line("G81 X0 Z-1 R1 L3", 5).ok());
}

TEST(GcodeModal, M2ResetsTheModesButKeepsOffsets) {
  Interpreter in;
  ASSERT_TRUE(in.execute_line("G55 G18 G91 G93 M3 S100 M8 G92 X5", 1).ok());
  ASSERT_TRUE(in.execute_line("G43.1 Z2", 1).ok());
  const LineResult r = in.execute_line("M2", 2);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(in.program_ended());
  const ModalState& m = in.modal();
  EXPECT_EQ(m.coord_system, 0);
  EXPECT_EQ(m.plane, Plane::xy);
  EXPECT_EQ(m.distance, Distance::absolute);
  EXPECT_EQ(m.feed_mode, FeedMode::units_per_minute);
  EXPECT_EQ(m.spindle, SpindleState::off);
  EXPECT_FALSE(m.flood);
  EXPECT_DOUBLE_EQ(m.tool_length_mm, 2.0);
  EXPECT_DOUBLE_EQ(in.data().g92[0], -5.0);
  ASSERT_FALSE(r.calls.empty());
  EXPECT_TRUE(std::holds_alternative<ProgramStop>(r.calls.back().op));
  // A line server goes on after M2.
  EXPECT_TRUE(in.execute_line("G0 X1", 3).ok());
  EXPECT_FALSE(in.program_ended());
}

TEST(GcodeModal, ProbeEndIsOnlyABeliefTheCallerCorrects) {
  Interpreter in;
  ASSERT_TRUE(in.execute_line("F10 G38.2 Z-10", 1).ok());
  EXPECT_TRUE(near3(in.machine_position(), {0, 0, -10}));
  in.set_machine_position({0, 0, -3.2});
  const LineResult r = in.execute_line("G91 G0 Z1", 2);
  EXPECT_TRUE(near3(end_of(r.calls.back().op), {0, 0, -2.2}));
}

TEST(GcodeCanon, ToStringIsOneReadableLine) {
  const auto c = calls_of("F300 G2 X1 Y1 R1\n");
  EXPECT_EQ(to_string(c.back()), "1 ARC_FEED end=(1,1,0) centre=(1,0,0) plane=17 cw turns=1 feed=300");
}
