// The Grbl 1.1 protocol engine (host/grbl/protocol.hpp) on the dry-run
// machine: replies byte for byte as Grbl 1.1h gives them, flow control,
// real-time bytes, every $ command, alarms, holds and overrides.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>

#include "tests/grbl_rig.hpp"

namespace mc::grbl::test {
namespace {

const std::string kBannerLine = "\r\nGrbl 1.1h ['$' for help]\r\n";

gcode::Vec3 end_of(const gcode::CanonCall& c) {
  if (const auto* f = std::get_if<gcode::StraightFeed>(&c.op)) return f->end;
  if (const auto* t = std::get_if<gcode::StraightTraverse>(&c.op)) return t->end;
  ADD_FAILURE() << "not a straight move: " << gcode::to_string(c);
  return {};
}

TEST(GrblProtocol, PowerUpPrintsTheBannerOnly) {
  Rig r;
  EXPECT_EQ(r.out, kBannerLine);
  EXPECT_EQ(r.engine->state(), "Idle");
  EXPECT_EQ(r.send(""), "");
}

// $MPG and $LEV are MotionCore's; on a machine without a handwheel or a
// height map (the dry-run machine) they say "setting disabled".
TEST(GrblProtocol, HandwheelAndLevellingWithoutThemAreSettingDisabled) {
  Rig r;
  EXPECT_EQ(r.send("$MPG\n"), "error:5\r\n");
  EXPECT_EQ(r.send("$MPG=X10\n"), "error:5\r\n");
  EXPECT_EQ(r.send("$LEV\n"), "[LEV:OFF]\r\nok\r\n");
  EXPECT_EQ(r.send("$LEV=1\n"), "error:5\r\n");
  EXPECT_EQ(r.send("$LEV=0\n"), "ok\r\n");
  EXPECT_EQ(r.send("$LEV=2\n"), "error:3\r\n");
}

TEST(GrblProtocol, OneAnswerPerLineWithGrblsErrorCodes) {
  Rig r;
  EXPECT_EQ(r.send("G21\n"), "ok\r\n");
  EXPECT_EQ(r.send("\n"), "ok\r\n");  // empty line: ok, for syncing
  EXPECT_EQ(r.send("(only a comment)\n"), "ok\r\n");
  EXPECT_EQ(r.send("G12\n"), "error:20\r\n");     // unsupported command
  EXPECT_EQ(r.send("G0G1X1\n"), "error:21\r\n");  // modal group violation
  EXPECT_EQ(r.send("G1X1\n"), "error:22\r\n");    // no feed rate yet
  EXPECT_EQ(r.send("G0X1X2\n"), "error:25\r\n");  // repeated word
  EXPECT_EQ(r.send("$Q\n"), "error:2\r\n");       // not a setting number (Grbl: bad number)
  EXPECT_EQ(r.send("$GX\n"), "error:3\r\n");      // no such $ command
  // Grbl ends a line at CR and at LF: CR LF is two lines, two answers.
  EXPECT_EQ(r.send("G21\r\n"), "ok\r\nok\r\n");
  EXPECT_EQ(r.engine->lines_answered(), 11u);
}

TEST(GrblProtocol, LinesAreCleanedAsGrblDoes) {
  Rig r;
  EXPECT_EQ(r.send("g1 x 1.5 (a comment) y-2 f 600 ; the rest\n"), "ok\r\n");
  ASSERT_EQ(r.backend.received().size(), 1u);
  const auto& calls = r.backend.received()[0].calls;
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(end_of(calls[0]), (gcode::Vec3{1.5, -2, 0}));
  // 79 characters after cleaning fit; 80 overflow (error:11) and the line
  // does nothing; comments and blanks do not count.
  const std::string fits = "G0X1" + std::string(75, '0');
  EXPECT_EQ(r.send(fits + "   (" + std::string(100, 'c') + ")\n"), "ok\r\n");
  EXPECT_EQ(r.send(fits + "0\n"), "error:11\r\n");
  EXPECT_EQ(r.send("G21\n"), "ok\r\n");
}

TEST(GrblProtocol, RealTimeBytesActInsideALine) {
  Rig r;
  // The `?` in the middle of the line is answered at once and is not part of it.
  const std::string a = r.send("G1X1?");
  EXPECT_TRUE(std::regex_match(a, std::regex("<Idle\\|MPos:[^>]*>\r\n"))) << a;
  EXPECT_EQ(r.send("0F600\n"), "ok\r\n");
  ASSERT_EQ(r.backend.received().size(), 1u);
  EXPECT_EQ(end_of(r.backend.received()[0].calls[0]), (gcode::Vec3{10, 0, 0}));
  // Bytes >= 0x80 that are no command vanish; 0x84 (door) is not supported.
  EXPECT_EQ(r.send("\xA5G\x84"
                   "21\xFE\n"),
            "ok\r\n");
}

TEST(GrblProtocol, StatusReportFieldsAndRefreshSchedule) {
  Rig r;
  std::vector<std::string> reports;
  for (int i = 0; i < 30; ++i) reports.push_back(r.status());
  EXPECT_EQ(reports[0], "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>");
  EXPECT_EQ(reports[1], "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Ov:100,100,100>");
  EXPECT_EQ(reports[2], "<Idle|MPos:0.000,0.000,0.000|FS:0,0>");
  for (size_t i = 0; i < reports.size(); ++i) {
    // Idle: WCO every 10th report (1st, 11th, 21st), Ov one report later.
    EXPECT_EQ(reports[i].find("WCO:") != std::string::npos, i % 10 == 0) << i << ": " << reports[i];
    EXPECT_EQ(reports[i].find("Ov:") != std::string::npos, i % 10 == 1) << i << ": " << reports[i];
  }
  // A new offset shows at once; $10=2 gives WPos and Bf:.
  EXPECT_EQ(r.send("G10L2P1X5Y-1\n"), "ok\r\n");
  EXPECT_EQ(r.status(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:5.000,-1.000,0.000>");
  EXPECT_EQ(r.send("$10=2\n"), "ok\r\n");
  EXPECT_EQ(r.status(), "<Idle|WPos:-5.000,1.000,0.000|Bf:4,128|FS:0,0|WCO:5.000,-1.000,0.000>");
  // Inches ($13=1): four decimals.
  EXPECT_EQ(r.send("$13=1\n"), "ok\r\n");
  EXPECT_EQ(r.status(), "<Idle|WPos:-0.1969,0.0394,0.0000|Bf:4,128|FS:0.0,0|WCO:0.1969,-0.0394,0.0000>");
}

TEST(GrblProtocol, RunningReportShowsFeedLineNumberAndAccessories) {
  Rig r;
  EXPECT_EQ(r.send("$10=3\n"), "ok\r\n");
  EXPECT_EQ(r.send("N12M3S1000\n"), "ok\r\n");
  EXPECT_EQ(r.send("N13G1X20F600\n"), "ok\r\n");
  r.run(1.0);
  r.status();  // spend the WCO report
  const std::string s = r.status();
  // 600 mm/min reached after 20 ms at 500 mm/s^2; 20 mm take 2 s.
  EXPECT_EQ(s.substr(0, 5), "<Run|") << s;
  EXPECT_NE(s.find("|Bf:3,128|Ln:13|FS:600,1000"), std::string::npos) << s;
  EXPECT_NE(s.find("|Ov:100,100,100|A:S>"), std::string::npos) << s;
}

TEST(GrblProtocol, OkComesWhenTheLineIsInThePlanner) {
  Rig r(test_defaults(), 4);  // four planner blocks, the clock stopped
  std::string out;
  for (int i = 1; i <= 8; ++i) out += r.send("G1X" + std::to_string(i) + "F6000\n");
  // Four lines fit the planner; the fifth waits outside the buffer and the
  // rest wait in it, unanswered.
  EXPECT_EQ(out, "ok\r\nok\r\nok\r\nok\r\n");
  EXPECT_EQ(r.engine->buffered(), 3 * std::string("G1X8F6000\n").size());
  EXPECT_EQ(r.engine->state(), "Run");
  // As the machine completes blocks, the rest are answered in order.
  out = r.run_until_idle();
  EXPECT_EQ(out, "ok\r\nok\r\nok\r\nok\r\n");
  EXPECT_EQ(r.backend.received().size(), 8u);
  EXPECT_EQ(r.backend.status().position, (gcode::Vec3{8, 0, 0}));
}

TEST(GrblProtocol, FeedHoldStopsOnThePathAndCycleStartResumes) {
  Rig r;
  EXPECT_EQ(r.send("G1X50F3000\n"), "ok\r\n");
  r.run(0.5);
  EXPECT_EQ(r.engine->state(), "Run");
  r.send("!");
  r.run(0.01);
  EXPECT_EQ(r.engine->state(), "Hold:1");  // decelerating: 50 mm/s at 500 mm/s^2 takes 100 ms
  r.run(0.2);
  EXPECT_EQ(r.engine->state(), "Hold:0");
  const double x = r.backend.status().position[0];
  EXPECT_GT(x, 10);
  EXPECT_LT(x, 50);
  r.run(1.0);
  EXPECT_EQ(r.backend.status().position[0], x);  // held means still
  r.send("~");
  r.run(0.05);
  EXPECT_EQ(r.engine->state(), "Run");
  r.run_until_idle();
  EXPECT_EQ(r.backend.status().position, (gcode::Vec3{50, 0, 0}));
  // A hold while idle is Hold:0 at once, and new lines wait in it.
  r.send("!");
  EXPECT_EQ(r.engine->state(), "Hold:0");
  EXPECT_EQ(r.send("G0X0\n"), "ok\r\n");
  r.run(0.5);
  EXPECT_EQ(r.backend.status().position[0], 50);
  r.send("~");
  r.run_until_idle();
  EXPECT_EQ(r.backend.status().position[0], 0);
}

TEST(GrblProtocol, OverridesClampStepAndReset) {
  Rig r;
  r.status();
  r.status();                  // past the first WCO and Ov reports
  r.send("\x91\x91\x91\x93");  // +10 +10 +10 +1
  EXPECT_NE(r.status().find("|Ov:131,100,100"), std::string::npos);
  EXPECT_EQ(r.backend.overrides().feed, 131);
  for (int i = 0; i < 20; ++i) r.send("\x91");
  EXPECT_EQ(r.engine->overrides().feed, 200);
  for (int i = 0; i < 30; ++i) r.send("\x92");
  EXPECT_EQ(r.engine->overrides().feed, 10);
  r.send("\x90\x97\x9A\x9A\x9D");
  EXPECT_EQ(r.backend.overrides(), (Overrides{100, 25, 119}));
  r.send("\x96");
  EXPECT_EQ(r.backend.overrides().rapid, 50);
  r.send("\x95\x99\x9B\x9B");
  EXPECT_EQ(r.backend.overrides(), (Overrides{100, 100, 80}));
  // A feed override changes the speed of the move in progress.
  r.send("\x99G1X100F1200\n");
  r.run(0.5);
  EXPECT_NEAR(r.backend.status().feed_mm_min, 1200, 1e-6);
  r.send("\x92\x92\x92\x92\x92");  // 50 %
  r.run(0.5);
  EXPECT_NEAR(r.backend.status().feed_mm_min, 600, 1e-6);
}

TEST(GrblProtocol, DwellAnswersAfterTheQueueDrainedAndTheDwellRan) {
  Rig r;
  EXPECT_EQ(r.send("G1X10F600\nG4P0.5\nG0X0\n"), "ok\r\n");
  // 10 mm at 600 mm/min: 1 s (plus 20 ms to accelerate), then 0.5 s.
  std::string out = r.run(1.4);
  EXPECT_EQ(out, "");
  out = r.run_until("ok");
  // G4's ok, and at once G0X0's: it only now left the buffer.
  EXPECT_EQ(out, "ok\r\nok\r\n");
  EXPECT_GE(r.backend.time_s(), 1.5);
  EXPECT_LE(r.backend.time_s(), 1.55);
  EXPECT_EQ(r.backend.status().position[0], 10);
}

TEST(GrblProtocol, ProbeReportsBeforeItsOk) {
  Rig r;
  r.backend.set_probe_surface(-2.5);
  EXPECT_EQ(r.send("G38.2Z-10F100\n"), "");
  EXPECT_EQ(r.run_until("ok"), "[PRB:0.000,0.000,-2.500:1]\r\nok\r\n");
  EXPECT_EQ(r.backend.status().position[2], -2.5);
  // The parser continues from the contact point, and $# shows it.
  EXPECT_EQ(r.send("G91G0Z1\nG90\n"), "ok\r\nok\r\n");
  r.run_until_idle();
  EXPECT_DOUBLE_EQ(r.backend.status().position[2], -1.5);
  const std::string p = r.send("$#\n");
  EXPECT_NE(p.find("[PRB:0.000,0.000,-2.500:1]\r\nok\r\n"), std::string::npos) << p;
  // No contact: G38.3 is fine, G38.2 is ALARM:5.
  r.backend.set_probe_surface(std::nullopt);
  r.send("G38.3Z-3F300\n");
  EXPECT_EQ(r.run_until("ok"), "[PRB:0.000,0.000,-3.000:0]\r\nok\r\n");
  r.send("G38.2Z-4F300\n");
  EXPECT_EQ(r.run_until("ok"), "ALARM:5\r\n[PRB:0.000,0.000,-4.000:0]\r\nok\r\n");
  EXPECT_EQ(r.engine->state(), "Alarm");
  // Already touching: ALARM:4 from the machine, the line answered error:9.
  EXPECT_EQ(r.send("$X\n"), "[MSG:Caution: Unlocked]\r\nok\r\n");
  r.backend.set_probe_surface(0.0);
  r.send("G38.2Z-5F300\n");
  EXPECT_EQ(r.run_until("error"), "ALARM:4\r\nerror:9\r\n");
}

TEST(GrblProtocol, SoftResetWhileMovingAlarmsAndLocks) {
  Rig r;
  EXPECT_EQ(r.send("G1X50F3000\nG1Y5\n"), "ok\r\nok\r\n");
  r.run(0.3);
  const std::string out = r.send("\x18");
  EXPECT_EQ(out, "ALARM:3\r\n" + kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  EXPECT_EQ(r.engine->state(), "Alarm");
  EXPECT_TRUE(r.backend.drained());
  EXPECT_EQ(r.send("G0X0\n"), "error:9\r\n");
  EXPECT_EQ(r.send("$X\n"), "[MSG:Caution: Unlocked]\r\nok\r\n");
  // The parser starts from where the machine stopped.
  const double x = r.backend.status().position[0];
  EXPECT_EQ(r.send("G91G0X1\n"), "ok\r\n");
  r.run_until_idle();
  EXPECT_NEAR(r.backend.status().position[0], x + 1, 1e-9);
  // A reset while idle (or in a finished hold) is the banner only.
  EXPECT_EQ(r.send("\x18"), kBannerLine);
  EXPECT_EQ(r.engine->state(), "Idle");
  // A reset drops what is in the receive buffer.
  r.send("!G1X80F3000\nG1X81\n");
  EXPECT_EQ(r.engine->state(), "Hold:0");
  EXPECT_EQ(r.send("\x18"), kBannerLine);
  r.run_until_idle();
  EXPECT_NEAR(r.backend.status().position[0], x + 1, 1e-9);
}

TEST(GrblProtocol, BoardFaultsAreAlarmsWithAMessage) {
  Rig r;
  EXPECT_EQ(r.send("G1X50F3000\n"), "ok\r\n");
  r.run(0.2);
  r.backend.inject_fault({3, "following error on X", true});
  EXPECT_EQ(r.run(0.01), "ALARM:3\r\n[MSG:following error on X]\r\n[MSG:Reset to continue]\r\n");
  // Critical: nothing but `?` and reset until a reset.
  EXPECT_EQ(r.send("$X\nG0X0\n"), "");
  EXPECT_EQ(r.status().substr(0, 7), "<Alarm|");
  EXPECT_EQ(r.send("\x18"), kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  EXPECT_EQ(r.send("$X\n"), "[MSG:Caution: Unlocked]\r\nok\r\n");
  // A non-critical one: the waiting line is answered error:9, then $X.
  Rig q(test_defaults(), 1);
  EXPECT_EQ(q.send("G1X50F3000\nG1X0\n"), "ok\r\n");
  q.backend.inject_fault({3, "watchdog", false});
  EXPECT_EQ(q.run(0.01), "ALARM:3\r\n[MSG:watchdog]\r\nerror:9\r\n");
  EXPECT_EQ(q.send("G0X0\n$X\n"), "error:9\r\n[MSG:Caution: Unlocked]\r\nok\r\n");
}

TEST(GrblProtocol, SettingsListChangeAndPersist) {
  Rig r;
  const std::string all = r.send("$$\n");
  EXPECT_EQ(count(all, "\r\n"), setting_numbers().size() + 1);
  EXPECT_EQ(all.substr(0, 7), "$0=10\r\n");
  EXPECT_NE(all.find("\r\n$11=0.010\r\n$12=0.002\r\n"), std::string::npos) << all;
  EXPECT_NE(all.find("\r\n$100=400.000\r\n"), std::string::npos) << all;
  EXPECT_NE(all.find("\r\n$132=200.000\r\nok\r\n"), std::string::npos) << all;
  EXPECT_EQ(r.send("$110=1234.5\n"), "ok\r\n");
  ASSERT_EQ(r.saves.size(), 1u);
  EXPECT_EQ(r.saves.back().settings.max_rate_mm_min[0], 1234.5);
  EXPECT_EQ(r.backend.settings().max_rate_mm_min[0], 1234.5);
  EXPECT_EQ(r.send("$110=-1\n"), "error:4\r\n");
  EXPECT_EQ(r.send("$20=1\n"), "error:10\r\n");  // soft limits need homing
  EXPECT_EQ(r.send("$22=1\n$20=1\n"), "ok\r\nok\r\n");
  EXPECT_EQ(r.send("$22=0\n"), "ok\r\n");  // homing off takes soft limits with it
  EXPECT_FALSE(r.engine->stored().settings.soft_limits);
  EXPECT_EQ(r.send("$7=1\n"), "error:3\r\n");
  EXPECT_EQ(r.send("$256=1\n"), "error:3\r\n");
  EXPECT_EQ(r.send("$1=\n"), "error:2\r\n");
  EXPECT_EQ(r.send("$1\n"), "error:3\r\n");
  EXPECT_EQ(r.saves.size(), 4u);
  // Not while running.
  EXPECT_EQ(r.send("G1X10F600\n"), "ok\r\n");
  EXPECT_EQ(r.send("$$\n$1=5\n"), "error:8\r\nerror:8\r\n");
  r.run_until_idle();
  EXPECT_EQ(r.send("$1=5\n"), "ok\r\n");
  // $RST=$ restores the defaults and resets.
  EXPECT_EQ(r.send("$RST=$\n"), "[MSG:Restoring defaults]\r\nok\r\n" + kBannerLine);
  EXPECT_EQ(r.engine->stored().settings.max_rate_mm_min[0], 6000);
}

TEST(GrblProtocol, OffsetsPersistAndG92DoesNot) {
  Rig r;
  EXPECT_EQ(r.send("G10L2P2X1Y2Z3\nG92X7\nG28.1\n"), "ok\r\nok\r\nok\r\n");
  const std::string p = r.send("$#\n");
  EXPECT_EQ(p,
            "[G54:0.000,0.000,0.000]\r\n[G55:1.000,2.000,3.000]\r\n[G56:0.000,0.000,0.000]\r\n"
            "[G57:0.000,0.000,0.000]\r\n[G58:0.000,0.000,0.000]\r\n[G59:0.000,0.000,0.000]\r\n"
            "[G28:0.000,0.000,0.000]\r\n[G30:0.000,0.000,0.000]\r\n[G92:-7.000,0.000,0.000]\r\n"
            "[TLO:0.000]\r\n[PRB:0.000,0.000,0.000:0]\r\nok\r\n");
  ASSERT_FALSE(r.saves.empty());
  EXPECT_EQ(r.saves.back().offsets.coord_offsets[1], (gcode::Vec3{1, 2, 3}));
  EXPECT_EQ(r.saves.back().offsets.g92, (gcode::Vec3{}));
  // A new engine on the saved data has G55 but no G92 (Grbl clears it on reset).
  Rig again(r.saves.back());
  const std::string q = again.send("$#\n");
  EXPECT_NE(q.find("[G55:1.000,2.000,3.000]"), std::string::npos);
  EXPECT_NE(q.find("[G92:0.000,0.000,0.000]"), std::string::npos);
  EXPECT_EQ(r.send("\x18"), kBannerLine);
  EXPECT_NE(r.send("$#\n").find("[G92:0.000,0.000,0.000]"), std::string::npos);
}

TEST(GrblProtocol, ParserStateBuildInfoAndHelp) {
  Rig r;
  EXPECT_EQ(r.send("$G\n"), "[GC:G80 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
  EXPECT_EQ(r.send("G20G91G56M8F10\n$G\n"), "ok\r\n[GC:G80 G56 G17 G20 G91 G94 M5 M8 T0 F10 S0]\r\nok\r\n");
  r.run(0.01);  // the coolant call goes through the queue
  EXPECT_EQ(r.send("$I\n"), "[VER:1.1h.20190830:]\r\n[OPT:VNM,4,128]\r\nok\r\n");
  EXPECT_EQ(r.send("$I=my router\n"), "ok\r\n");
  EXPECT_EQ(r.send("$I\n"), "[VER:1.1h.20190830:MYROUTER]\r\n[OPT:VNM,4,128]\r\nok\r\n");
  EXPECT_EQ(r.send("$\n"),
            "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\nok\r\n");
}

TEST(GrblProtocol, StartupBlocksRunAfterReset) {
  Rig r;
  EXPECT_EQ(r.send("$N\n"), "$N0=\r\n$N1=\r\nok\r\n");
  EXPECT_EQ(r.send("$N0=G20 G55\n"), "ok\r\n");
  EXPECT_EQ(r.send("$N1=G12\n"), "error:20\r\n");  // checked before it is stored
  EXPECT_EQ(r.send("$N2=G20\n"), "error:3\r\n");   // two blocks only
  EXPECT_EQ(r.send("$N\n"), "$N0=G20G55\r\n$N1=\r\nok\r\n");
  EXPECT_EQ(r.saves.back().startup[0], "G20G55");
  EXPECT_EQ(r.send("\x18"), kBannerLine + ">G20G55:ok\r\n");
  EXPECT_EQ(r.send("$G\n"), "[GC:G80 G55 G17 G20 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
  // Not run when the reset ends in an alarm.
  r.send("G1X5F6000\n");
  r.run(0.05);
  EXPECT_EQ(r.send("\x18"), "ALARM:3\r\n" + kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  EXPECT_EQ(r.send("$N0=G21\n"), "error:8\r\n");  // storing needs Idle
}

TEST(GrblProtocol, CheckModeParsesButDoesNotMove) {
  Rig r;
  EXPECT_EQ(r.send("$C\n"), "[MSG:Enabled]\r\nok\r\n");
  EXPECT_EQ(r.engine->state(), "Check");
  EXPECT_EQ(r.send("G1X10F100\nG4P10\nG12\nG10L2P1X3\n"), "ok\r\nok\r\nerror:20\r\nok\r\n");
  EXPECT_TRUE(r.backend.received().empty());
  EXPECT_TRUE(r.saves.empty());
  EXPECT_EQ(r.send("$C\n"), "[MSG:Disabled]\r\nok\r\n" + kBannerLine);
  EXPECT_EQ(r.engine->state(), "Idle");
  EXPECT_EQ(r.engine->interpreter().machine_position(), (gcode::Vec3{}));
  EXPECT_NE(r.send("$#\n").find("[G54:0.000,0.000,0.000]"), std::string::npos);
}

TEST(GrblProtocol, HomingIsNotEnabled) {
  Rig r;
  EXPECT_EQ(r.send("$H\n"), "error:5\r\n");
  Stored s = test_defaults();
  s.settings.homing = true;
  Rig h(s);  // homing on: locked at power-up, as Grbl's HOMING_INIT_LOCK
  EXPECT_EQ(h.out, kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  EXPECT_EQ(h.send("G0X1\n"), "error:9\r\n");
  EXPECT_EQ(h.send("$H\n"), "error:5\r\n");  // the dry-run machine cannot home
  EXPECT_EQ(h.send("$X\nG0X-1\n"), "[MSG:Caution: Unlocked]\r\nok\r\nok\r\n");
}

TEST(GrblProtocol, JoggingFollowsGrblsRules) {
  Rig r;
  EXPECT_EQ(r.send("$J=G91X10F600\n"), "ok\r\n");
  ASSERT_EQ(r.backend.received().size(), 1u);
  EXPECT_TRUE(r.backend.received()[0].jog);
  r.run(0.1);
  EXPECT_EQ(r.engine->state(), "Jog");
  EXPECT_EQ(r.send("G0X0\n"), "error:9\r\n");     // g-code is locked out while jogging
  EXPECT_EQ(r.send("$J=G91X1F600\n"), "ok\r\n");  // jogs queue behind jogs
  r.send("\x85");                                 // jog cancel: decelerate, drop the queued jogs
  r.run(0.1);
  EXPECT_EQ(r.engine->state(), "Idle");
  const double x = r.backend.status().position[0];
  EXPECT_GT(x, 0);
  EXPECT_LT(x, 10);
  // The parser continues from where the jog stopped and kept its modes (G90).
  EXPECT_EQ(r.send("G0Y1\n"), "ok\r\n");
  r.run_until_idle();
  EXPECT_EQ(r.backend.status().position, (gcode::Vec3{x, 1, 0}));
  // G20 and G53 apply to the jog only; the modal state does not change.
  EXPECT_EQ(r.send("G10L2P1X5\n$J=G20G53X1F10\n"), "ok\r\nok\r\n");
  r.run_until_idle();
  EXPECT_NEAR(r.backend.status().position[0], 25.4, 1e-9);
  EXPECT_EQ(r.send("$G\n"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
  EXPECT_EQ(r.send("$J=G1X1F100\n"), "error:16\r\n");
  EXPECT_EQ(r.send("$J=X1M3F100\n"), "error:16\r\n");
  EXPECT_EQ(r.send("$J=X1\n"), "error:22\r\n");
  EXPECT_EQ(r.send("$JX1F1\n"), "error:3\r\n");
  // A feed hold during a jog cancels it.
  EXPECT_EQ(r.send("$J=X100F3000\n"), "ok\r\n");
  r.run(0.2);
  r.send("!");
  r.run(0.3);
  EXPECT_EQ(r.engine->state(), "Idle");
  EXPECT_LT(r.backend.status().position[0], 100);
}

TEST(GrblProtocol, SoftLimitsAlarmAndLimitJogs) {
  Stored s = test_defaults();
  s.settings.homing = s.settings.soft_limits = true;
  Rig r(s);
  EXPECT_EQ(r.send("$X\n"), "[MSG:Caution: Unlocked]\r\nok\r\n");
  EXPECT_EQ(r.send("G0X-10\n"), "ok\r\n");  // inside: -200..0
  r.run_until_idle();
  EXPECT_EQ(r.send("$J=X5F100\n"), "error:15\r\n");  // jogs are refused, no alarm
  EXPECT_EQ(r.send("G0X10\n"), "ALARM:2\r\n[MSG:Reset to continue]\r\n");
  EXPECT_EQ(r.send("G0X-1\n"), "");
  EXPECT_EQ(r.send("\x18"), kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  // The machine's own travel: the top end at 20 mm, 120 mm of travel (-100..20).
  s.settings.travel_top_mm[2] = 20;
  s.settings.max_travel_mm[2] = 120;
  Rig z(s);
  EXPECT_EQ(z.send("$X\nG0Z20\nG0Z-100\n"), "[MSG:Caution: Unlocked]\r\nok\r\nok\r\nok\r\n");
  EXPECT_EQ(z.send("G0Z-100.001\n"), "ALARM:2\r\n[MSG:Reset to continue]\r\n");
}

TEST(GrblProtocol, ProgramPauseAndEnd) {
  Rig r;
  EXPECT_EQ(r.send("G1X1F600\nM0\nG1X2\n"), "ok\r\n");
  std::string out = r.run_until("ok");
  EXPECT_EQ(out, "ok\r\nok\r\n");  // M0's ok once X1 is reached; X2 queued behind the hold
  EXPECT_EQ(r.engine->state(), "Hold:0");
  r.run(0.5);
  EXPECT_EQ(r.backend.status().position[0], 1);
  r.send("~");
  r.run_until_idle();
  EXPECT_EQ(r.backend.status().position[0], 2);
  r.send("\x91");
  EXPECT_EQ(r.send("M3S100\nM2\n"), "ok\r\n");
  EXPECT_EQ(r.run_until("ok"), "[MSG:Pgm End]\r\nok\r\n");
  EXPECT_EQ(r.backend.overrides().feed, 100);  // M2 restores the overrides
  EXPECT_EQ(r.backend.status().spindle, 0);
}

TEST(GrblProtocol, SleepNeedsAReset) {
  Rig r;
  EXPECT_EQ(r.send("$SLP\n"), "[MSG:Sleeping]\r\nok\r\n");
  EXPECT_EQ(r.engine->state(), "Sleep");
  EXPECT_EQ(r.send("G0X1\n"), "");
  EXPECT_EQ(r.send("\x18"), kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
}

}  // namespace
}  // namespace mc::grbl::test

namespace mc::grbl::test {
namespace {

// A machine that can home: homing takes 0.3 s of board time, or fails when
// the test says so. It stands in for the machine-cycles work to come.
class HomingMachine : public DryRunBackend {
 public:
  HomingMachine() : DryRunBackend(4) {}
  int home(unsigned axis_mask) override {
    mask_ = axis_mask;
    left_s_ = 0.3;
    return 0;
  }
  Status status() const override {
    Status s = DryRunBackend::status();
    if (left_s_ > 0) s.motion = Motion::homing;
    return s;
  }
  void soft_reset() override {
    left_s_ = 0;
    DryRunBackend::soft_reset();
  }
  void step(double dt_s) {
    left_s_ -= dt_s;
    advance(dt_s);
  }
  unsigned mask_ = 0;
  double left_s_ = 0;
};

TEST(GrblProtocol, HomingUnlocksAndRunsTheStartupBlocks) {
  HomingMachine m;
  Stored s = test_defaults();
  s.settings.homing = true;
  s.startup[1] = "G20";
  EngineOptions o;
  o.stored = s;
  Engine e(m, o);
  EXPECT_EQ(e.take_output(), kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  e.receive("$H\n");
  e.poll();
  EXPECT_EQ(e.take_output(), "");
  EXPECT_EQ(e.state(), "Alarm");  // still locked while it homes
  for (int i = 0; i < 250; ++i) m.step(1e-3), e.poll();
  EXPECT_EQ(e.take_output(), "");
  for (int i = 0; i < 100; ++i) m.step(1e-3), e.poll();
  EXPECT_EQ(e.take_output(), "ok\r\n>G20:ok\r\n");
  EXPECT_EQ(m.mask_, 7u);
  EXPECT_EQ(e.state(), "Idle");
  // A reset while homing is ALARM:6; a failed cycle is the machine's alarm.
  e.receive("$H\n");
  e.poll();
  m.step(0.1);
  e.receive("\x18");
  EXPECT_EQ(e.take_output(), "ALARM:6\r\n" + kBannerLine + "[MSG:'$H'|'$X' to unlock]\r\n");
  e.receive("$H\n");
  e.poll();
  m.inject_fault({9, "", false});
  e.poll();
  EXPECT_EQ(e.take_output(), "ALARM:9\r\nerror:9\r\n");
  EXPECT_EQ(e.state(), "Alarm");
}

TEST(GrblProtocol, PinsShowInTheReport) {
  Rig r;
  r.status();
  r.backend.set_probe_surface(0.5);
  EXPECT_EQ(r.status(), "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Pn:P|Ov:100,100,100>");
}

}  // namespace
}  // namespace mc::grbl::test

namespace mc::grbl::test {
namespace {

TEST(GrblProtocol, ASenderIgnoringFlowControlLosesNothing) {
  // Grbl would drop what overflows its 128 bytes; here it waits (input_room()).
  Stored st = test_defaults();
  st.settings.report_mask = 3;
  Rig r(st);
  std::string all;
  for (int i = 1; i <= 500; ++i) all += "N" + std::to_string(i) + "G1X" + std::to_string(i % 7) + "F6000\n";
  EXPECT_GT(all.size(), 20 * kRxBufferSize);
  EXPECT_GE(r.engine->input_room(), all.size());
  std::string out = r.send(all);
  EXPECT_GT(r.engine->buffered(), kRxBufferSize);
  EXPECT_NE(r.status().find("|Bf:0,0|"), std::string::npos);  // planner full, buffer full
  out += r.run_until_idle(120);
  EXPECT_EQ(count(out, "ok\r\n"), 500u);
  EXPECT_EQ(out.size(), 500 * std::string("ok\r\n").size());
  ASSERT_EQ(r.backend.received().size(), 500u);
  for (size_t i = 0; i < 500; ++i) EXPECT_EQ(r.backend.received()[i].line_number, int(i + 1));
}

}  // namespace
}  // namespace mc::grbl::test
