// The tuning workflow through the real programs (issue 8): on a world whose
// robot has worn, slower motors with dead time (config/worlds/tuning_floor.yaml),
// pc_server records an identification wheel test, identifies the plant,
// tracks the 3.5 m circle with the paper's gains, tunes, pushes the tuned
// gains (acknowledged with a version) and tracks again. Ground truth
// (mcu_sim's pose log) must show the second circle tracked better.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <sstream>

#include "tests/support/stack.hpp"

using namespace inspect::test;

namespace {

struct CircleFigures {
  double t0 = 0, duration = 0;
  double max_radial = 0, rms_radial = 0;
};

// The circles in the truth log: stretches of >= 20 s of sim time driving
// forward (the wheel test spins on the spot, and goes straight for 1 s only). Radial error = | |p - centre| - r |, the centre
// 3.5 m to the left of the pose where the stretch starts.
std::vector<CircleFigures> circles(const Truth& truth, double r) {
  std::vector<CircleFigures> out;
  const auto& rows = truth.rows;
  std::size_t i = 0;
  const auto forward = [&](std::size_t k) { return (rows[k].set_l + rows[k].set_r) / 2.0; };
  while (i < rows.size()) {
    if (!(forward(i) > 1.0)) {
      ++i;
      continue;
    }
    // A circle at 0.5 m/s has a mean wheel set-point of 2.5 rad/s; an
    // oscillating wheel loop may dip for a moment, so dips under 0.5 s do not end it.
    std::size_t j = i, k = i;
    while (k + 1 < rows.size()) {
      ++k;
      if (forward(k) > 0.5) j = k;
      else if (rows[k].t - rows[j].t > 0.5) break;
    }
    if (rows[j].t - rows[i].t >= 20.0) {
      // The robot starts from rest: take the pose one tick before the set-points rose.
      const auto& s = rows[i > 0 ? i - 1 : i];
      const double cx = s.x - r * std::sin(s.theta), cy = s.y + r * std::cos(s.theta);
      CircleFigures c;
      c.t0 = rows[i].t;
      c.duration = rows[j].t - rows[i].t;
      double sum2 = 0;
      for (std::size_t n = i; n <= j; ++n) {
        const double e = std::abs(std::hypot(rows[n].x - cx, rows[n].y - cy) - r);
        c.max_radial = std::max(c.max_radial, e);
        sum2 += e * e;
      }
      c.rms_radial = std::sqrt(sum2 / static_cast<double>(j - i + 1));
      out.push_back(c);
    }
    i = j + 1;
  }
  return out;
}

}  // namespace

TEST(TuningStack, IdentifyTunePushAndTheCircleIsTrackedBetter) {
  std::ostringstream script;
  script << "expect robots >= 1 within 15\nexpect sensor_hz > 50 within 5\n"
         << "route " << srcPath("config/routes/identification.yaml") << "\n"
         << "expect mode == WHEEL_TEST within 2\nexpect mode == IDLE within 40\nwait 0.5\n"
         << "identify last\n"
         << "track circle 3.5 0.5 1 fuzzy_pid\nexpect mode == TRACKING within 2\nexpect mode == IDLE within 40\n"
         << "expect max_pos_err > 0\nexpect max_ang_err > 0\n"
         // 600 evaluations, not 400: offline, on 12 plants within +-3e-6 of one this test identified,
         // 400 left the seeded global search (GN_CRS2_LM, then LN_SBPLX) in a poor optimum for 2
         // (cost 84.8 and 240.5 against ~10; the tuned circle then tracked worse), 600 for none of
         // the 11 that finished (those two: 15.2 and 12.1). About 5 s more; the tuner's own default is 1000.
         << "tune evals=600\n"
         << "gains push\nexpect gains_version == 1 within 2\n"
         << "track circle 3.5 0.5 1 fuzzy_pid\nexpect mode == TRACKING within 2\nexpect mode == IDLE within 40\n"
         << "expect max_pos_err > 0\nexpect max_ang_err > 0\n"
         << "gains revert\nexpect gains_version == 2 within 2\ngains show\n";
  Stack s("tuning");
  ASSERT_TRUE(s.startServer(script.str())) << s.logs();
  // 3x real time: the robot's loop runs on the MCU clock, so the control is the same (telemetry
  // at 50 Hz of wall time is 17 Hz of sim time: enough to identify a 50 ms dead time).
  auto& robot = s.startRobot("robot1", "tuning_floor.yaml", {}, {"--rate", "3"});
  const auto rc = s.server().wait(170);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  const std::string out = s.serverOutput();
  std::printf("%s", out.c_str());
  EXPECT_EQ(*rc, 0) << s.logs();

  // Identification found the world's plant (gain 0.88 / 0.96, tau 0.32 / 0.28 s, dead 0.05 s + the loop's latency).
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(left  gain ([0-9.]+)  time constant ([0-9.]+) s  dead time ([0-9.]+) s)")))
      << out;
  EXPECT_NEAR(std::stod(m[1]), 0.88, 0.03);
  EXPECT_NEAR(std::stod(m[2]), 0.32, 0.04);
  EXPECT_GT(std::stod(m[3]), 0.045);
  EXPECT_LT(std::stod(m[3]), 0.08);
  EXPECT_NE(out.find("robot1: gains v1 accepted"), std::string::npos);
  EXPECT_NE(out.find("GAINS_APPLIED: gains v1 in force"), std::string::npos);
  EXPECT_NE(out.find("robot1: gains v2 accepted"), std::string::npos) << "revert pushes the previous set as v2";

  // The robot's own figures (odometry against the reference): better with the tuned gains.
  const double paper_pos = expectedValue(out, "max_pos_err", 0), tuned_pos = expectedValue(out, "max_pos_err", 1);
  const double paper_ang = expectedValue(out, "max_ang_err", 0), tuned_ang = expectedValue(out, "max_ang_err", 1);
  std::printf("TUNING robot max position error %.4f -> %.4f m, max angle error %.4f -> %.4f rad\n", paper_pos,
              tuned_pos, paper_ang, tuned_ang);
  EXPECT_LT(tuned_pos, paper_pos);
  EXPECT_LT(tuned_ang, paper_ang);

  // Ground truth.
  const auto truth = readTruth(robot.truth);
  const auto c = circles(truth, 3.5);
  ASSERT_EQ(c.size(), 2u) << "two circles in the truth log";
  for (const auto& f : c)
    std::printf("TUNING truth circle at t=%.1f s (%.1f s): max radial error %.4f m, RMS %.4f m\n", f.t0, f.duration,
                f.max_radial, f.rms_radial);
  EXPECT_LT(c[1].rms_radial, c[0].rms_radial);
  EXPECT_LT(c[1].max_radial, c[0].max_radial);
  // The session is on disk with its plots and in the catalog.
  const std::regex sess(R"(tune: session (\S+): \d+ files in (\S+)/)");
  ASSERT_TRUE(std::regex_search(out, m, sess)) << out;
  EXPECT_TRUE(std::filesystem::exists(std::string(m[2]) + "/summary.md"));
  EXPECT_TRUE(std::filesystem::exists(std::string(m[2]) + "/fig20_position_error.png"));
}
