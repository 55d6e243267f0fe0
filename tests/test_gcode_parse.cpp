// Parsing, modal groups and every error class of the G-code interpreter.
#include <gtest/gtest.h>

#include "gcode_helpers.hpp"
#include "host/gcode/block.hpp"

using namespace gcode_test;

// ---- lexical -------------------------------------------------------------

TEST(GcodeParse, SplitsWordsIgnoringBlanksCaseAndComments) {
  const ParsedLine p = parse_line("n10 g01 x 1 . 5 Y-.25 (a comment) z+3 ; the rest");
  ASSERT_FALSE(p.error) << p.error->format();
  ASSERT_TRUE(p.block.n);
  EXPECT_EQ(p.block.n->value, 10);
  ASSERT_EQ(p.block.g.size(), 1U);
  EXPECT_EQ(p.block.g[0].value, 1);
  EXPECT_EQ(p.block.g[0].text, "G01");
  EXPECT_DOUBLE_EQ(p.block.value('X'), 1.5);
  EXPECT_EQ(p.block.word('X')->text, "X1.5");
  EXPECT_EQ(p.block.word('X')->column, 9);
  EXPECT_DOUBLE_EQ(p.block.value('Y'), -0.25);
  EXPECT_DOUBLE_EQ(p.block.value('Z'), 3);
  EXPECT_FALSE(p.block.has('F'));
}

TEST(GcodeParse, SeveralGAndMWordsKeepTheirOrder) {
  const ParsedLine p = parse_line("G90 G21 G0 X1 M3 M8 S100");
  ASSERT_FALSE(p.error);
  ASSERT_EQ(p.block.g.size(), 3U);
  EXPECT_EQ(p.block.g[2].value, 0);
  ASSERT_EQ(p.block.m.size(), 2U);
  EXPECT_EQ(p.block.m[1].value, 8);
}

TEST(GcodeParse, PercentAndBlockDelete) {
  EXPECT_TRUE(parse_line("  %  ").block.percent);
  EXPECT_TRUE(parse_line("% (comment)").block.percent);
  EXPECT_TRUE(parse_line("%G1").error);
  const ParsedLine p = parse_line("/G1 X1");
  EXPECT_TRUE(p.block.block_delete);
  EXPECT_TRUE(parse_line("").block.g.empty());
  EXPECT_FALSE(parse_line("   ; only a comment").error);
}

struct LexCase {
  const char* line;
  int code;
  const char* word;
  int column;
};

class GcodeLexErrors : public ::testing::TestWithParam<LexCase> {};

TEST_P(GcodeLexErrors, NamesTheWordAndColumn) {
  const LexCase c = GetParam();
  const ParsedLine p = parse_line(c.line);
  ASSERT_TRUE(p.error) << c.line;
  EXPECT_EQ(p.error->grbl_code, c.code) << p.error->message;
  EXPECT_EQ(p.error->word, c.word);
  EXPECT_EQ(p.error->column, c.column);
  EXPECT_FALSE(p.error->message.empty());
}

INSTANTIATE_TEST_SUITE_P(Cases, GcodeLexErrors,
                         ::testing::Values(LexCase{"G1 X1 X2", grbl::word_repeated, "X2", 7},  //
                                           LexCase{"G1 X", grbl::bad_number_format, "X", 4},
                                           LexCase{"G1 X-", grbl::bad_number_format, "X", 4},
                                           LexCase{"G1 X#1", grbl::unsupported_command, "X#", 4},
                                           LexCase{"#1=2", grbl::unsupported_command, "#", 1},
                                           LexCase{"G1 X[1+2]", grbl::unsupported_command, "X[", 4},
                                           LexCase{"O100 sub", grbl::unsupported_command, "O100", 1},
                                           LexCase{"G0 A10", grbl::unsupported_command, "A10", 4},
                                           LexCase{"G41 D1", grbl::unsupported_command, "D1", 5},
                                           LexCase{"G43 H1", grbl::unsupported_command, "H1", 5},
                                           LexCase{"G1 @1 ^2", grbl::unsupported_command, "@", 4},
                                           LexCase{"G1 X1 (open", grbl::expected_command_letter, "(", 7},
                                           LexCase{"G1 (a (b) c)", grbl::expected_command_letter, "(", 7},
                                           LexCase{"G1 X1 $", grbl::expected_command_letter, "$", 7},
                                           LexCase{"G1 N5 X1", grbl::invalid_line_number, "N5", 4},
                                           LexCase{"N1.5 G1", grbl::invalid_line_number, "N1.5", 1}));

// ---- modal groups and word checks ----------------------------------------

struct ErrCase {
  const char* program;
  int code;
  const char* word;
  int line;
};

class GcodeErrors : public ::testing::TestWithParam<ErrCase> {};

TEST_P(GcodeErrors, RefusedWithGrblCodeAndWord) {
  const ErrCase c = GetParam();
  const Error e = error_of(c.program);
  EXPECT_EQ(e.grbl_code, c.code) << e.format();
  EXPECT_EQ(e.word, c.word) << e.format();
  EXPECT_EQ(e.line, c.line) << e.format();
  EXPECT_EQ(e.file, "t.ngc");
}

INSTANTIATE_TEST_SUITE_P(
    Cases, GcodeErrors,
    ::testing::Values(
        // modal group violations (21)
        ErrCase{"G0 X1 G1 Y2", grbl::modal_group_violation, "G1", 1},
        ErrCase{"G17 G18", grbl::modal_group_violation, "G18", 1},
        ErrCase{"G20 G21", grbl::modal_group_violation, "G21", 1},
        ErrCase{"G54 G55", grbl::modal_group_violation, "G55", 1},
        ErrCase{"G4 P1 G92 X0", grbl::modal_group_violation, "G92", 1},
        ErrCase{"M3 M5", grbl::modal_group_violation, "M5", 1},
        ErrCase{"M7 M8", grbl::modal_group_violation, "M8", 1},
        ErrCase{"M0 M1", grbl::modal_group_violation, "M1", 1},
        ErrCase{"G80 G0 X1", grbl::modal_group_violation, "G0", 1},
        // undefined feed (22)
        ErrCase{"G21\nG1 X5", grbl::undefined_feed_rate, "G1", 2},
        ErrCase{"G1 X5 F0", grbl::undefined_feed_rate, "G1", 1},
        ErrCase{"G93 G1 X1 F2\nG1 X2", grbl::undefined_feed_rate, "G1", 2},
        ErrCase{"F100\nG93\nG1 X1", grbl::undefined_feed_rate, "G1", 3},
        ErrCase{"G81 X1 Z-1 R1", grbl::undefined_feed_rate, "G81", 1},
        ErrCase{"G38.2 Z-1", grbl::undefined_feed_rate, "G38.2", 1},
        // not an integer (23)
        ErrCase{"M1.5", grbl::command_value_not_integer, "M1.5", 1},
        ErrCase{"T1.5", grbl::command_value_not_integer, "T1.5", 1},
        ErrCase{"F10 G81 X1 Z-1 R1 L1.5", grbl::command_value_not_integer, "L1.5", 1},
        ErrCase{"F10 G2 X0 I1 P1.5", grbl::command_value_not_integer, "P1.5", 1},
        ErrCase{"G10 L2 P1.5 X0", grbl::command_value_not_integer, "P1.5", 1},
        // axis command conflict (24)
        ErrCase{"G92 X1 G0 Y1", grbl::axis_command_conflict, "G0", 1},
        ErrCase{"G10 L2 P1 X1 G1 Y1 F1", grbl::axis_command_conflict, "G1", 1},
        ErrCase{"G28 X1 G0 Y1", grbl::axis_command_conflict, "G0", 1},
        ErrCase{"G43.1 Z1 G0 X1", grbl::axis_command_conflict, "G0", 1},
        // no axis words (26)
        ErrCase{"G92", grbl::no_axis_words, "G92", 1},
        // missing values (28)
        ErrCase{"G4", grbl::value_word_missing, "G4", 1},
        ErrCase{"G10 P1 X1", grbl::value_word_missing, "G10", 1},
        ErrCase{"G10 L2 X1", grbl::value_word_missing, "G10", 1},
        ErrCase{"F100 G81 X1 Z-1", grbl::value_word_missing, "G81", 1},
        ErrCase{"F100 G81 X1 R1", grbl::value_word_missing, "G81", 1},
        ErrCase{"F100 G83 X1 Z-1 R1", grbl::value_word_missing, "G83", 1},
        ErrCase{"F100 G73 X1 Z-1 R1", grbl::value_word_missing, "G73", 1},
        ErrCase{"F100 G82 X1 Z-1 R1", grbl::value_word_missing, "G82", 1},
        ErrCase{"F100 G81 X1 Z-1 R1 L0", grbl::value_word_missing, "L0", 1},
        // coordinate system (29)
        ErrCase{"G10 L2 P10 X1", grbl::unsupported_coord_sys, "P10", 1},
        // G53 (30)
        ErrCase{"F1 G53 G2 X1 I1", grbl::g53_invalid_motion_mode, "G53", 1},
        ErrCase{"G91 G53 G0 X1", grbl::g53_invalid_motion_mode, "G53", 1},
        ErrCase{"G80\nG53 X1", grbl::axis_words_exist, "X1", 2},
        // axis words with nothing to use them (31)
        ErrCase{"G80 X1", grbl::axis_words_exist, "X1", 1},
        ErrCase{"G80\nY1", grbl::axis_words_exist, "Y1", 2},
        ErrCase{"G28.1 X1", grbl::axis_words_exist, "X1", 1},
        ErrCase{"G92.1 Z1", grbl::axis_words_exist, "Z1", 1},
        // invalid target (33)
        ErrCase{"F1 G2 X0 Y0 R1", grbl::invalid_target, "R1", 1},
        ErrCase{"F1 G38.2 X0", grbl::invalid_target, "G38.2", 1},
        // arc radius (34)
        ErrCase{"F1 G2 X10 I4", grbl::arc_radius_error, "G2", 1},
        ErrCase{"F1 G2 X10 R4.9", grbl::arc_radius_error, "R4.9", 1},
        ErrCase{"F1 G2 X10 I0 J0", grbl::arc_radius_error, "G2", 1},
        // no offsets in plane (35)
        ErrCase{"F1 G2 X10", grbl::no_offsets_in_plane, "G2", 1},
        ErrCase{"F1 G90.1 G2 X10 I5", grbl::no_offsets_in_plane, "G2", 1},
        // unused words (36)
        ErrCase{"F1 G1 X1 I1", grbl::unused_words, "I1", 1},
        ErrCase{"F1 G17 G2 X2 I1 K1", grbl::unused_words, "K1", 1},
        ErrCase{"F1 G18 G2 X2 I1 J1", grbl::unused_words, "J1", 1},
        ErrCase{"F1 G2 X2 I1 R1", grbl::unused_words, "R1", 1},
        ErrCase{"G0 X1 R5", grbl::unused_words, "R5", 1}, ErrCase{"G0 X1 P1", grbl::unused_words, "P1", 1},
        ErrCase{"G0 X1 Q1", grbl::unused_words, "Q1", 1}, ErrCase{"G0 X1 L2", grbl::unused_words, "L2", 1},
        // G43.1 (37)
        ErrCase{"G43.1 X1", grbl::g43_dynamic_axis_error, "X1", 1},
        ErrCase{"G43.1", grbl::g43_dynamic_axis_error, "G43.1", 1},
        // negative values (4)
        ErrCase{"G4 P-1", grbl::negative_value, "P-1", 1},
        ErrCase{"G1 X1 F-5", grbl::negative_value, "F-5", 1}, ErrCase{"S-5", grbl::negative_value, "S-5", 1},
        ErrCase{"F100 G83 X1 Z-1 R1 Q0", grbl::negative_value, "Q0", 1},
        ErrCase{"G64 P-1", grbl::negative_value, "P-1", 1}));

// The refused features name their word and say it is not supported.
struct RefusedCase {
  const char* program;
  const char* word;
  const char* says;
};

class GcodeRefused : public ::testing::TestWithParam<RefusedCase> {};

TEST_P(GcodeRefused, ClearErrorNamingTheWord) {
  const RefusedCase c = GetParam();
  const Error e = error_of(c.program);
  EXPECT_EQ(e.grbl_code, grbl::unsupported_command) << e.format();
  EXPECT_EQ(e.word, c.word);
  EXPECT_NE(e.message.find(c.says), std::string::npos) << e.message;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, GcodeRefused,
    ::testing::Values(
        RefusedCase{"G41 X1", "G41", "cutter radius compensation"},
        RefusedCase{"G42.1 X1", "G42.1", "cutter radius compensation"}, RefusedCase{"G16", "G16", "polar"},
        RefusedCase{"G33 X1 K1", "G33", "threading"}, RefusedCase{"G76 P1", "G76", "threading"},
        RefusedCase{"G7", "G7", "lathe"}, RefusedCase{"G71", "G71", "lathe"},
        RefusedCase{"G84 X1 Z-1 R1", "G84", "G73, G81, G82 and G83"}, RefusedCase{"G43", "G43", "G43.1"},
        RefusedCase{"G5.2", "G5.2", "splines"}, RefusedCase{"G1.5 X1", "G1.5", "unsupported G code"},
        RefusedCase{"M98 P100", "M98", "subroutine"}, RefusedCase{"M62 P1", "M62", "I/O"},
        RefusedCase{"M200", "M200", "unsupported M code"},
        RefusedCase{"G10 L1 P1 Z1", "L1", "G10 L2 and G10 L20"},
        RefusedCase{"G10 L2 P1 R45", "R45", "rotation"}, RefusedCase{"G64 P0.1 Q0.05", "Q0.05", "G64 Q"},
        RefusedCase{"G1 X#1", "X#", "parameters"}, RefusedCase{"o10 if [1]", "O10", "O-word"}));

TEST(GcodeErrorFormat, FileLineColumnWordMessageAndCode) {
  const Error e = error_of("G21\nG90\nG0 X1 G41 Y2\n");
  EXPECT_EQ(
      e.format(),
      "t.ngc:3:7: error: G41: cutter radius compensation is not supported: program the tool centre path "
      "(G40 is accepted) (grbl error:20)");
  Error bare;
  bare.line = 4;
  bare.column = 1;
  bare.message = "something";
  EXPECT_EQ(bare.format(), "4:1: error: something");
}

TEST(GcodeErrorFormat, MessageSaysWhatWasExpected) {
  EXPECT_NE(error_of("G4").message.find("P, the dwell time"), std::string::npos);
  EXPECT_NE(error_of("G1 X1").message.find("give F"), std::string::npos);
  EXPECT_NE(error_of("F1 G81 X1 Z-1").message.find("needs R"), std::string::npos);
}

// ---- whole files ---------------------------------------------------------

TEST(GcodeFile, AnErrorAnywhereMovesNothingAndEveryBadLineIsReported) {
  const ProgramResult r = run("G21 F100\nG1 X1\nG1 X2 X3\nG1 X4\nG41 X5\nG1 X6\nM2\n");
  EXPECT_FALSE(r.ok());
  EXPECT_TRUE(r.calls.empty());
  ASSERT_EQ(r.errors.size(), 2U);
  EXPECT_EQ(r.errors[0].line, 3);
  EXPECT_EQ(r.errors[1].line, 5);
}

TEST(GcodeFile, PercentDelimitsTheProgramAndM2EndsIt) {
  const auto c1 = calls_of("%\nG0 X1\n%\nG0 X2\n");
  EXPECT_EQ(ends(c1).size(), 1U);
  const ProgramResult r = run("G0 X1\nM2\nthis is not G-code\n");
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.lines, 2);
  const auto c3 = calls_of("G0 X1\nM30\nG0 X2\n");
  EXPECT_EQ(ends(c3).size(), 1U);
  // A file without an end is accepted (as Grbl does; LinuxCNC wants M2 or %).
  EXPECT_TRUE(run("G0 X1\n").ok());
}

TEST(GcodeFile, CrLfLinesAndErrorsCountLinesFromOne) {
  const ProgramResult r = run("G21\r\nG0 X1\r\nG0 Y1 Y2\r\n");
  ASSERT_EQ(r.errors.size(), 1U);
  EXPECT_EQ(r.errors[0].line, 3);
  EXPECT_EQ(r.errors[0].column, 7);
}

TEST(GcodeFile, BlockDeleteSwitch) {
  EXPECT_EQ(ends(calls_of("G0 X1\n/G0 X2\n")).size(), 2U);
  Options skip;
  skip.block_delete = true;
  EXPECT_EQ(ends(calls_of("G0 X1\n/G0 X2\n", skip)).size(), 1U);
  // A skipped line is not even checked.
  EXPECT_TRUE(run("/G41 X1\n", skip).ok());
}

TEST(GcodeFile, UnreadableFileIsOneError) {
  const ProgramResult r = interpret_file("/nonexistent/x.ngc");
  ASSERT_EQ(r.errors.size(), 1U);
  EXPECT_EQ(r.errors[0].file, "/nonexistent/x.ngc");
}
