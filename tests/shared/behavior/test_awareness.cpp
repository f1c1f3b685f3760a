// What the robot does about people (shared/behavior/human_awareness) and the
// tracker's use of the front sensor pair and of negative information, with
// synthetic echoes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shared/behavior/human_awareness.hpp"
#include "tests/shared/behavior/sonar_echoes.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using behavior::AwarenessConfig;
using behavior::HumanAwareness;
using behavior::HumanTracker;
using behavior::SpeedPolicy;
using test::Circle;
using test::echoes;

namespace {

const std::string kFis = inspect::test::srcPath("config/fuzzy/speed_strategy.fis");

HumanAwareness make(SpeedPolicy policy, AwarenessConfig cfg = {}) {
  cfg.policy = policy;
  const config::UltrasonicConfig u;
  return HumanAwareness(u, cfg, behavior::loadSpeedStrategy(kFis, cfg.speed));
}

// Mean |estimated - true| lateral position of an oncoming person 0.5 m to the
// left while it is 3.5 .. 1.8 m ahead of a robot standing still.
double lateralError(bool triangulate) {
  const config::UltrasonicConfig u;
  behavior::HumanTrackerParams p;
  p.triangulate_front = triangulate;
  HumanTracker tr(u, p);
  std::mt19937 rng(5);
  const control::Pose2 robot{0, 0, 0};
  double sum = 0;
  int n = 0;
  for (int k = 0; k < 340; ++k) {
    const double t = k * 0.01;
    const double x = 3.7 - 0.5 * t;
    tr.step(robot, echoes(u, robot, {{x, 0.5, 0.25}}, {}, &rng), t);
    if (k >= 100)
      if (const auto* tk = tr.nearest(robot)) {
        sum += std::abs(tk->x[1] - 0.5);
        ++n;
      }
  }
  return n > 0 ? sum / n : 1e9;
}

}  // namespace

TEST(HumanTracker, FrontPairFixesTheBearingThatOneConeCannot) {
  const double fused = lateralError(true);
  const double centre = lateralError(false);
  std::printf("mean lateral error: fused %.3f m, beam centres %.3f m\n", fused, centre);
  EXPECT_LT(fused, 0.2);
  EXPECT_LT(fused, 0.6 * centre);
}

TEST(HumanTracker, ATrackASensorSeesThroughIsDroppedNotCoasted) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  const control::Pose2 robot{0, 0, 0};
  // An oncoming person straight ahead, then gone (stepped out of view behind a
  // shelf end): the front sensors now hear the far wall at 4 m.
  const std::vector<geometry::Segment> far_wall{{4.2, -3, 4.2, 3}};
  int k = 0;
  for (; k < 200; ++k) tr.step(robot, echoes(u, robot, {{3.0 - 0.5 * k * 0.01, 0.0, 0.25}}, {}), k * 0.01);
  ASSERT_NE(tr.nearest(robot), nullptr);
  int gone_after = -1;
  for (int j = 0; j < 100; ++j, ++k) {
    tr.step(robot, echoes(u, robot, {}, far_wall), k * 0.01);
    if (!tr.nearest(robot)) {
      gone_after = j + 1;
      break;
    }
  }
  EXPECT_GE(gone_after, 1);
  EXPECT_LE(gone_after, 5) << "dropped within a few ticks, not after coast_s";
  EXPECT_GE(tr.counters().tracks_contradicted, 1u);
}

TEST(HumanAwareness, StopAndWaitStopsInsideTheAvoidanceDistanceOnly) {
  auto a = make(SpeedPolicy::kStopAndWait);
  const config::UltrasonicConfig u;
  const control::Pose2 robot{0, 0, 0};
  double factor_far = -1, factor_near = -1;
  for (int k = 0; k < 500; ++k) {
    const double t = k * 0.01, x = 4.4 - 0.5 * t;  // 4.4 m -> 1.9 m
    const auto& r = a.step(robot, echoes(u, robot, {{x, 0.0, 0.25}}, {}), t);
    if (r.person && r.distance_m > 3.3 && factor_far < 0) factor_far = r.target_factor;
    if (r.person && r.distance_m < 2.5) factor_near = r.target_factor;
  }
  EXPECT_EQ(factor_far, 1.0);
  EXPECT_EQ(factor_near, 0.0);
  EXPECT_EQ(a.last().speed_factor, 0.0);
}

TEST(HumanAwareness, PolicyNoneTracksButNeverSlows) {
  auto a = make(SpeedPolicy::kNone);
  const config::UltrasonicConfig u;
  const control::Pose2 robot{0, 0, 0};
  bool seen = false;
  for (int k = 0; k < 500; ++k) {
    const auto& r = a.step(robot, echoes(u, robot, {{3.5 - 0.5 * k * 0.01, 0.0, 0.25}}, {}), k * 0.01);
    seen = seen || r.person;
    ASSERT_EQ(r.speed_factor, 1.0);
  }
  EXPECT_TRUE(seen);
}

TEST(HumanAwareness, AppliedFactorChangesNoFasterThanItsRateLimits) {
  AwarenessConfig cfg;
  auto a = make(SpeedPolicy::kStopAndWait, cfg);
  const config::UltrasonicConfig u;
  const control::Pose2 robot{0, 0, 0};
  double prev = 1.0, min_seen = 1.0;
  for (int k = 0; k < 900; ++k) {
    const double t = k * 0.01;
    // A person appears 2 m ahead, stands 3 s, then is gone.
    const std::vector<Circle> people = t < 4.0 ? std::vector<Circle>{{2.0 + 0.3 * std::sin(3 * t), 0, 0.25}}
                                               : std::vector<Circle>{};
    const auto& r = a.step(robot, echoes(u, robot, people, {}), t);
    if (k > 0) {
      EXPECT_GE(r.speed_factor, prev - cfg.factor_fall_per_s * 0.01 - 1e-9) << "t " << t;
      EXPECT_LE(r.speed_factor, prev + cfg.factor_rise_per_s * 0.01 + 1e-9) << "t " << t;
    }
    prev = r.speed_factor;
    min_seen = std::min(min_seen, r.speed_factor);
  }
  EXPECT_EQ(min_seen, 0.0);   // it did stop
  EXPECT_EQ(prev, 1.0);       // and came back to full speed
}

TEST(HumanAwareness, APersonPassingBesideNoLongerSlowsTheRobot) {
  auto a = make(SpeedPolicy::kFuzzy);
  const config::UltrasonicConfig u;
  // The robot drives at 0.3 m/s; a person walks the other way 0.8 m to its
  // left and is met beside it: the left sensor sees them pass.
  double passing_factor = -1;
  bool passing_seen = false;
  for (int k = 0; k < 600; ++k) {
    const double t = k * 0.01;
    const control::Pose2 robot{0.3 * t, 0, 0};
    const Circle p{1.2 - 0.5 * t, 0.8, 0.25};
    const auto& r = a.step(robot, echoes(u, robot, {p}, {}), t);
    if (r.person && r.passing) {
      passing_seen = true;
      passing_factor = r.target_factor;
    }
  }
  ASSERT_TRUE(passing_seen);
  EXPECT_EQ(passing_factor, 1.0);
}

TEST(HumanAwareness, PolicyFromConfigAndBadPolicyNamed) {
  const auto c = behavior::loadAwarenessConfig(
      config::ConfigNode::loadString("awareness: {policy: stop_and_wait, factor_fall_per_s: 4}\n", "b.yaml"), ".");
  EXPECT_EQ(c.policy, SpeedPolicy::kStopAndWait);
  EXPECT_EQ(c.factor_fall_per_s, 4.0);
  try {
    behavior::loadAwarenessConfig(config::ConfigNode::loadString("awareness: {policy: dance}\n", "b.yaml"), ".");
    FAIL() << "accepted an unknown policy";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("policy"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dance"), std::string::npos) << e.what();
  }
}

// Found by fuzz_config: a stop zone beyond the avoidance distance was refused
// by the speed strategy's own check, whose message named neither the file
// nor the key.
TEST(HumanAwareness, SensitiveBeyondAvoidanceIsRefusedNamingFileAndKey) {
  try {
    behavior::loadAwarenessConfig(
        config::ConfigNode::loadString("awareness: {max_avoidance_m: 1.0, sensitive_m: 1.2}\n", "b.yaml"), ".");
    FAIL() << "accepted sensitive_m beyond max_avoidance_m";
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("b.yaml", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("sensitive_m"), std::string::npos) << e.what();
  }
}

TEST(HumanTracker, APersonWhoStopsIsStillAPerson) {
  // Walks towards the robot, then stands 8 s 2 m ahead (reading a gauge): the
  // robot must keep them as a person, not learn them as structure.
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::mt19937 rng(11);
  const control::Pose2 robot{0, 0, 0};
  int lost_ticks = 0;
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 0.01;
    const double x = t < 2.0 ? 3.0 - 0.5 * t : 2.0;
    tr.step(robot, echoes(u, robot, {{x, 0.0, 0.25}}, {}, &rng), t);
    if (t > 2.0 && !tr.nearest(robot)) ++lost_ticks;
  }
  EXPECT_EQ(lost_ticks, 0);
  EXPECT_EQ(tr.counters().tracks_static_dropped, 0u);
}

TEST(HumanAwareness, PredictsAnOncomingPersonAndUsesEq8) {
  AwarenessConfig cfg;
  cfg.predict_horizon_s = 1.0;
  auto a = make(SpeedPolicy::kFuzzy, cfg);
  const config::UltrasonicConfig u;
  bool anticipated = false;
  for (int k = 0; k < 400; ++k) {
    const double t = k * 0.01;
    const control::Pose2 robot{0.4 * t, 0, 0};  // the robot drives at 0.4 m/s
    const auto& r = a.step(robot, echoes(u, robot, {{4.4 - 0.5 * t, 0.1, 0.25}}, {}), t);
    if (r.person && r.predicted_min_m >= 0 && r.distance_m > 2.0) {
      // Closing at ~0.9 m/s: in 1 s the gap shrinks by ~0.9 m (nearer, the
      // model has the person give way to the robot, as the simulator's do).
      EXPECT_LT(r.predicted_min_m, r.distance_m - 0.5) << "t " << t;
      EXPECT_NEAR(r.predicted_at_s, 1.0, 1e-9);
      // Eq 8: R_avoid - v t with v ~ 0.4 m/s and t = 1 s.
      EXPECT_NEAR(r.avoid_m, cfg.speed.max_avoidance_m - 0.4, 0.1);
      anticipated = anticipated || r.anticipating;
    }
  }
  EXPECT_TRUE(anticipated);

  cfg.predict_horizon_s = 0.0;
  auto off = make(SpeedPolicy::kFuzzy, cfg);
  for (int k = 0; k < 400; ++k) {
    const double t = k * 0.01;
    const control::Pose2 robot{0.4 * t, 0, 0};
    const auto& r = off.step(robot, echoes(u, robot, {{4.4 - 0.5 * t, 0.1, 0.25}}, {}), t);
    ASSERT_FALSE(r.anticipating);
    ASSERT_LT(r.predicted_min_m, 0.0);
  }
}
