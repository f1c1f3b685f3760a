// The three real programs on loopback: mcu_sim on a real pty, robot_client,
// pc_server driven by a console script. Ground truth comes from mcu_sim.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"

using namespace inspect::test;

namespace {

constexpr double kPi = std::numbers::pi;

double wrap(double a) { return std::remainder(a, 2 * kPi); }

struct Rel {
  double x, y, th;
};

// Pose of `r` in the frame of the robot's start pose `s`.
Rel relative(const TruthRow& s, const TruthRow& r) {
  const double dx = r.x - s.x, dy = r.y - s.y, c = std::cos(s.theta), sn = std::sin(s.theta);
  return {c * dx + sn * dy, -sn * dx + c * dy, wrap(r.theta - s.theta)};
}

// The last row of every period of >= 0.3 s in which the wheels stood still.
std::vector<TruthRow> restPoses(const Truth& t) {
  std::vector<TruthRow> out;
  std::size_t start = 0;
  bool in_rest = false;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const bool still = std::abs(r.wheel_l) < 0.02 && std::abs(r.wheel_r) < 0.02 && r.set_l == 0 && r.set_r == 0;
    if (still && !in_rest) {
      start = i;
      in_rest = true;
    }
    if ((!still || i + 1 == t.rows.size()) && in_rest) {
      const std::size_t end = still ? i : i - 1;
      if (t.rows[end].t - t.rows[start].t >= 0.3) out.push_back(t.rows[end]);
      in_rest = false;
    }
  }
  return out;
}

bool atSpeed(const std::string& truth, double wheel_rad_s) {
  const auto t = readTruth(truth);
  if (t.rows.size() < 20) return false;
  for (std::size_t i = t.rows.size() - 20; i < t.rows.size(); ++i)
    if (std::abs(t.rows[i].wheel_l) < wheel_rad_s || std::abs(t.rows[i].wheel_r) < wheel_rad_s) return false;
  return true;
}

const char* kConnect = "expect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\nexpect mode == IDLE\n";

}  // namespace

TEST(System, ScriptedSquareDriveReachesExpectedPoses) {
  Stack s("square");
  s.catchUpAfterStalls();  // the legs are timed by the console's wall clock
  std::ostringstream script;
  script << kConnect << "wait 1\n";
  // Four legs of 1.0 m (0.5 m/s for 2 s) and four left turns of 90 deg
  // (1 rad/s for pi/2 s), stopping in between; 1.5 s to come to rest (a
  // rest counts from 0.3 s below 0.02 rad/s: ~1.1 s after the stop, with the
  // set-point's slew and the wheels' 0.2 s time constant).
  const double turn_s = kPi / 2 / 1.0;
  const double corners[4][3] = {{1, 0, 0}, {1, 1, kPi / 2}, {0, 1, kPi}, {0, 0, -kPi / 2}};
  for (int leg = 0; leg < 4; ++leg) {
    script << "drive 0.5 0\nwait 2\nstop\nwait 1.5\n";
    script << "expect x ~ " << corners[leg][0] << " 0.05\nexpect y ~ " << corners[leg][1] << " 0.05\n";
    script << "drive 0 1.0\nwait " << turn_s << "\nstop\nwait 1.5\n";
  }
  script << "expect x ~ 0 0.05\nexpect y ~ 0 0.05\nexpect theta ~ 0 0.05\nstatus\n";
  ASSERT_TRUE(s.startServer(script.str())) << s.logs();
  auto& r = s.startRobot("robot1");
  const auto rc = s.server().wait(90);
  ASSERT_TRUE(rc.has_value()) << "script did not finish\n" << s.logs();
  EXPECT_EQ(*rc, 0) << "a console expect failed (telemetry pose)\n" << s.serverOutput();

  const auto truth = readTruth(r.truth);
  const auto rest = restPoses(truth);
  ASSERT_GE(rest.size(), 9u) << s.logs();
  // rest[0] is the start; then one rest after every leg and every turn.
  const Rel expected[9] = {{0, 0, 0},         {1, 0, 0},         {1, 0, kPi / 2}, {1, 1, kPi / 2}, {1, 1, kPi},
                           {0, 1, kPi},       {0, 1, -kPi / 2},  {0, 0, -kPi / 2}, {0, 0, 0}};
  double worst_pos = 0, worst_ang = 0;
  for (int i = 0; i < 9; ++i) {
    const Rel got = relative(rest[0], rest[static_cast<std::size_t>(i)]);
    const double dp = std::hypot(got.x - expected[i].x, got.y - expected[i].y);
    const double da = std::abs(wrap(got.th - expected[i].th));
    worst_pos = std::max(worst_pos, dp);
    worst_ang = std::max(worst_ang, da);
    EXPECT_LE(dp, 0.05) << "pose " << i << ": (" << got.x << ", " << got.y << ")";
    EXPECT_LE(da, 0.05) << "pose " << i << ": theta " << got.th;
  }
  std::printf("SQUARE worst position error %.4f m, worst heading error %.4f rad over 9 poses\n", worst_pos, worst_ang);
}

TEST(System, EStopHoldsUntilResume) {
  Stack s("estop");
  std::string script = kConnect;
  script +=
      "drive 0.2 0\nexpect v ~ 0.2 0.03 within 3\n"
      "estop\nexpect mode == ESTOP within 1\nexpect v ~ 0 0.01 within 1\n"
      "try drive 0.2 0\nwait 1\nexpect v ~ 0 0.01\nexpect mode == ESTOP\n"
      "stop\nwait 0.5\nexpect mode == ESTOP\n"
      "resume\nexpect mode == IDLE within 1\n"
      "drive 0.2 0\nexpect v ~ 0.2 0.03 within 3\nstop\nexpect v ~ 0 0.01 within 2\n";
  ASSERT_TRUE(s.startServer(script)) << s.logs();
  s.startRobot("robot1");
  const auto rc = s.server().wait(60);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  EXPECT_EQ(*rc, 0) << s.serverOutput();
}




// Killing the server or the client mid-drive, and garbage and bit errors on
// the serial line, are fault_inject's (tests/system/faults: fault_inject_short, every
// fault through these same programs against ground truth; fault_inject_ber).

TEST(System, SecondRobotConnectsWhileFirstDrives) {
  Stack s("tworobots");
  std::string script =
      "select robot1\nexpect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\n"
      "drive 0 0.5\nexpect w ~ 0.5 0.1 within 3\n"
      "expect robots == 2 within 20\n"
      "expect w ~ 0.5 0.1\n"
      "select robot2\nexpect connected == 1\nexpect sensor_hz > 50 within 5\n"
      "drive 0 -0.5\nexpect w ~ -0.5 0.1 within 3\nwait 3\n"
      "select robot1\nexpect w ~ 0.5 0.1\nstop\n"
      "select robot2\nstop\nexpect w ~ 0 0.02 within 2\n";
  ASSERT_TRUE(s.startServer(script)) << s.logs();
  auto& r1 = s.startRobot("robot1");
  ASSERT_TRUE(waitUntil([&] { return atSpeed(r1.truth, 0.4); }, 20)) << s.logs();
  const int64_t t2 = nowNs();
  s.startRobot("robot2");
  const auto rc = s.server().wait(60);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  EXPECT_EQ(*rc, 0) << s.serverOutput();
  // robot1 never slowed while robot2 connected and drove (robot1 is stopped
  // by the script only after robot2 has driven for 3 s).
  const auto truth = readTruth(r1.truth);
  std::size_t checked = 0;
  for (const auto& row : truth.rows) {
    if (row.mono_ns < t2 || row.mono_ns > t2 + 3'000'000'000LL) continue;
    ++checked;
    EXPECT_GT(std::abs(row.set_r), 0.4) << "robot1 slowed at t=" << row.t;
  }
  EXPECT_GT(checked, 200u);
}

// Issue 9: the link is mutual TLS, and nothing secret reaches a log or a
// recording: no line of the robot's or the server's private key appears in any
// file the programs wrote (logs, run.mcap, the catalog, the MP4).
TEST(System, NoPrivateKeyInLogsOrRecordings) {
  Stack s("secrets");
  std::string script = kConnect;
  script += "record start secrets\ndrive 0.2 0\nwait 2\nstop\nrecord stop\n";
  ASSERT_TRUE(s.startServer(script)) << s.logs();
  s.startRobot("robot1");
  const auto rc = s.server().wait(60);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  EXPECT_EQ(*rc, 0) << s.serverOutput();
  const std::string out = s.serverOutput();
  EXPECT_NE(out.find("(mutual TLS, server certificate CN=pc_server"), std::string::npos) << out;
  // The base64 lines of both keys (each 64 characters of key material, or the last shorter one).
  std::vector<std::string> secret_lines;
  for (const char* key : {"robot1.key", "server.key"}) {
    std::istringstream in(readFile(testCertsDir({"robot1"}) + "/" + key));
    for (std::string line; std::getline(in, line);)
      if (line.rfind("-----", 0) != 0 && line.size() >= 16) secret_lines.push_back(line);
  }
  ASSERT_GE(secret_lines.size(), 4u);
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(s.dir().path())) {
    if (!entry.is_regular_file()) continue;
    const std::string text = readFile(entry.path().string());
    ++files;
    EXPECT_EQ(text.find("PRIVATE KEY"), std::string::npos) << entry.path();
    for (const auto& l : secret_lines) EXPECT_EQ(text.find(l), std::string::npos) << entry.path();
  }
  EXPECT_GE(files, 8);  // logs of 3 programs, truth, run.mcap, catalog, ...
}
