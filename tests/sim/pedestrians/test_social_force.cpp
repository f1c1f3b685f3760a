// The social force model (shared/behavior/social_force.*) closed-loop on toy
// scenes: relaxation to the desired speed, passing in a corridor, walls, the
// robot, degenerate input, anisotropy, prediction and Eq 8.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "shared/behavior/social_force.hpp"

using namespace inspect::behavior;
using V = Eigen::Vector2d;

namespace {

constexpr double kDt_s = 0.001;  // the simulator's physics step

bool finite(const V& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }

Agent walker(V pos, V goal_dir, double v0 = 0.5) {
  Agent a;
  a.position_m = pos;
  a.goal_direction = goal_dir.normalized();
  a.desired_speed_m_s = v0;
  a.velocity_m_s = v0 * a.goal_direction;
  return a;
}

// Points the agent at `goal` (zero once within 5 cm), as a route follower does.
void aimAt(Agent& a, const V& goal) {
  const V d = goal - a.position_m;
  a.goal_direction = d.norm() > 0.05 ? V(d.normalized()) : V::Zero();
}

double wallDistance(const WallSegment& s, const V& p) {
  return inspect::geometry::pointSegmentDistance({p.x(), p.y()}, s.edge);
}

// A wall from a to b (Eigen points), its ends joined to other walls or not.
WallSegment wallOf(const V& a, const V& b, bool a_joined = false, bool b_joined = false) {
  return {{{a.x(), a.y()}, {b.x(), b.y()}}, a_joined, b_joined};
}

}  // namespace

TEST(SocialForce, LoneWalkerRelaxesToDesiredSpeedWithTau) {
  const SocialForceParams p;  // tau = 0.5 s
  Agent a;
  a.goal_direction = V(1, 0);
  a.desired_speed_m_s = 0.5;
  double max_speed = 0.0;
  for (int k = 1; k <= 5000; ++k) {
    integrate(a, computeForce(a, {}, {}, nullptr, p).total(), p, kDt_s);
    max_speed = std::max(max_speed, a.velocity_m_s.norm());
    const double t = k * kDt_s;
    if (k == 500) {
      EXPECT_NEAR(a.velocity_m_s.x(), 0.5 * (1 - std::exp(-t / 0.5)), 0.002);  // one tau: 63 %
    }
    if (k == 1500) {
      EXPECT_GT(a.velocity_m_s.x(), 0.95 * 0.5);  // three tau: 95 %
    }
  }
  EXPECT_NEAR(a.velocity_m_s.x(), 0.5, 1e-3);
  EXPECT_NEAR(a.velocity_m_s.y(), 0.0, 1e-12);
  EXPECT_LE(max_speed, 0.5 + 1e-9);
}

TEST(SocialForce, LoneWalkerReachesGoalAtAboutV0) {
  const SocialForceParams p;
  Agent a;  // at rest at the origin
  a.desired_speed_m_s = 0.5;
  const V goal(3.0, 4.0);  // 5 m away
  double arrived_s = -1.0;
  for (int k = 1; k <= 20000 && arrived_s < 0; ++k) {
    aimAt(a, goal);
    integrate(a, computeForce(a, {}, {}, nullptr, p).total(), p, kDt_s);
    if ((a.position_m - goal).norm() < 0.05) arrived_s = k * kDt_s;
  }
  // 5 m at 0.5 m/s is 10 s, plus about one tau of acceleration lag.
  ASSERT_GT(arrived_s, 0.0);
  EXPECT_GT(arrived_s, 10.0);
  EXPECT_LT(arrived_s, 10.0 + 3 * p.relaxation_time_s);
}

TEST(SocialForce, SpeedIsCappedAtMaxFactorTimesV0) {
  const SocialForceParams p;
  Agent a = walker(V(0, 0), V(1, 0));
  integrate(a, V(1000.0, 0.0), p, 0.01);  // a huge push
  EXPECT_NEAR(a.velocity_m_s.norm(), 1.3 * 0.5, 1e-12);
}

// --- two people head-on in a 3 m corridor ---

struct HeadOnCase {
  double offset_m;   // lateral offset between the two walking lines
  double speed_m_s;  // desired speed of both
  double min_gap_m;  // the body gap they must keep at least
};

class HeadOn : public ::testing::TestWithParam<HeadOnCase> {};

TEST_P(HeadOn, PassEachOtherWithoutOverlap) {
  const auto c = GetParam();
  const SocialForceParams p;
  const std::vector<WallSegment> walls{wallOf(V(-20, -1.5), V(40, -1.5)), wallOf(V(-20, 1.5), V(40, 1.5))};
  std::vector<Agent> a{walker(V(0, c.offset_m / 2), V(1, 0), c.speed_m_s),
                       walker(V(10, -c.offset_m / 2), V(-1, 0), c.speed_m_s)};
  std::vector<V> scratch(2);
  double min_d = 1e9, min_wall = 1e9;
  const int steps = static_cast<int>((10.0 / c.speed_m_s + 10.0) / kDt_s);
  for (int k = 0; k < steps; ++k) {
    stepAgents(a, walls, nullptr, p, kDt_s, scratch);
    min_d = std::min(min_d, (a[0].position_m - a[1].position_m).norm());
    for (const auto& ag : a)
      for (const auto& w : walls) min_wall = std::min(min_wall, wallDistance(w, ag.position_m));
  }
  EXPECT_GT(min_d, 0.5 + c.min_gap_m) << "closest centres " << min_d;
  EXPECT_GT(min_wall, 0.25) << "a body touched a wall";
  EXPECT_GT(a[0].position_m.x(), 12.0) << "did not get past";
  EXPECT_LT(a[1].position_m.x(), -2.0) << "did not get past";
  ::testing::Test::RecordProperty("min_gap_m", std::to_string(min_d - 0.5));
}

INSTANTIATE_TEST_SUITE_P(Corridor, HeadOn,
                         ::testing::Values(HeadOnCase{0.0, 0.5, 0.30},   // dead ahead: sidestep to the right
                                           HeadOnCase{0.1, 0.5, 0.30},   //
                                           HeadOnCase{0.3, 0.5, 0.40},   //
                                           HeadOnCase{0.6, 0.5, 0.50},   //
                                           HeadOnCase{0.0, 1.3, 0.02},   // fast walkers: close, but no overlap
                                           HeadOnCase{0.3, 1.3, 0.05}));

TEST(SocialForce, DeadAheadPassesKeepingRight) {
  const SocialForceParams p;
  std::vector<Agent> a{walker(V(0, 0), V(1, 0)), walker(V(10, 0), V(-1, 0))};
  std::vector<V> scratch(2);
  for (int k = 0; k < 12000; ++k) stepAgents(a, {}, nullptr, p, kDt_s, scratch);  // 12 s: they meet at ~10 s
  // Each went to its own right: the one walking +x to -y, the other to +y.
  EXPECT_LT(a[0].position_m.y(), -0.2);
  EXPECT_GT(a[1].position_m.y(), 0.2);
}

TEST(SocialForce, WalkingAlongAWallKeepsClearance) {
  const SocialForceParams p;
  const std::vector<WallSegment> wall{wallOf(V(-10, 0), V(40, 0))};
  Agent a = walker(V(0, 0.30), V(1, 0));  // starts 5 cm off the wall with its body
  double min_c = 1e9;
  for (int k = 0; k < 20000; ++k) {
    integrate(a, computeForce(a, {}, wall, nullptr, p).total(), p, kDt_s);
    min_c = std::min(min_c, a.position_m.y());
  }
  EXPECT_GE(min_c, 0.30 - 1e-6) << "moved closer to the wall";
  EXPECT_GT(a.position_m.y(), 0.25 + 0.2) << "clearance after 20 s";
  EXPECT_LT(a.position_m.y(), 1.5) << "pushed unreasonably far from a wall";
  EXPECT_GT(a.position_m.x(), 9.0) << "kept walking";
}

TEST(SocialForce, WalkingIntoAWallStopsBeforeIt) {
  const SocialForceParams p;
  const std::vector<WallSegment> wall{wallOf(V(2, -5), V(2, 5))};
  Agent a = walker(V(0, 0), V(1, 0));  // wants to walk through the wall at x = 2
  double max_x = -1e9;
  for (int k = 0; k < 20000; ++k) {
    integrate(a, computeForce(a, {}, wall, nullptr, p).total(), p, kDt_s);
    max_x = std::max(max_x, a.position_m.x());
  }
  EXPECT_LT(max_x, 2.0 - 0.25) << "the body overlapped the wall";
}

// A box as four joined edges, as the simulator builds obstacles.
std::vector<WallSegment> box(double x0, double y0, double x1, double y1) {
  const V c[4] = {V(x0, y0), V(x1, y0), V(x1, y1), V(x0, y1)};
  std::vector<WallSegment> w;
  for (int i = 0; i < 4; ++i) w.push_back(wallOf(c[i], c[(i + 1) % 4], true, true));
  return w;
}

TEST(SocialForce, A80cmDoorwayIsPassableAt05MetresPerSecond) {
  const SocialForceParams p;
  auto walls = box(2, 0.4, 2.3, 3);  // two boxes 0.3 m deep leaving a 0.8 m gap around y = 0
  const auto lower = box(2, -3, 2.3, -0.4);
  walls.insert(walls.end(), lower.begin(), lower.end());
  for (double offset : {0.0, 0.1}) {
    Agent a;
    a.position_m = V(0, offset);
    a.desired_speed_m_s = 0.5;
    const V goal(5, offset);
    double through_s = -1, min_wall = 1e9;
    for (int k = 0; k < 20000 && through_s < 0; ++k) {
      aimAt(a, goal);
      integrate(a, computeForce(a, {}, walls, nullptr, p).total(), p, kDt_s);
      for (const auto& w : walls) min_wall = std::min(min_wall, wallDistance(w, a.position_m));
      if (a.position_m.x() > 4.5) through_s = k * kDt_s;
    }
    EXPECT_GT(through_s, 0.0) << "stuck in front of the doorway, offset " << offset;
    EXPECT_LT(through_s, 4.5 / 0.5 + 2.0) << offset;
    EXPECT_GT(min_wall, 0.25) << "a body overlapped a door post, offset " << offset;
  }
}

TEST(SocialForce, ASharedCornerCountsOnce) {
  const SocialForceParams p;
  // Two edges of a polygon meeting at (1, 1).
  const std::vector<WallSegment> joined{wallOf(V(1, 0), V(1, 1), true, true), wallOf(V(1, 1), V(0, 1), true, true)};
  std::vector<WallSegment> loose = joined;
  for (auto& w : loose) w.a_joined = w.b_joined = false;
  Agent a;
  a.position_m = V(1.3, 1.3);  // beyond the corner (1, 1): both edges' nearest point is the corner
  const std::vector<WallSegment> corner_edge{wallOf(V(1, 0), V(1, 1))};
  const V single = computeForce(a, {}, corner_edge, nullptr, p).walls_m_s2;
  EXPECT_TRUE(computeForce(a, {}, joined, nullptr, p).walls_m_s2.isApprox(single, 1e-9));
  EXPECT_TRUE(computeForce(a, {}, loose, nullptr, p).walls_m_s2.isApprox(2 * single, 1e-9));
}

class RobotInTheWay : public ::testing::TestWithParam<double> {};

TEST_P(RobotInTheWay, StandingRobotIsWalkedAround) {
  const double offset_m = GetParam();  // of the route from the robot's centre
  const SocialForceParams p;
  Agent robot;
  robot.position_m = V(3, 0);
  robot.radius_m = 0.35;
  Agent a = walker(V(0, offset_m), V(1, 0));
  const V goal(8, offset_m);
  double min_d = 1e9, max_dev = 0.0;
  for (int k = 0; k < 30000; ++k) {
    aimAt(a, goal);
    integrate(a, computeForce(a, {}, {}, &robot, p).total(), p, kDt_s);
    min_d = std::min(min_d, (a.position_m - robot.position_m).norm());
    max_dev = std::max(max_dev, std::abs(a.position_m.y() - offset_m));
  }
  EXPECT_GT(min_d, 0.35 + 0.25 + 0.2) << "passed closer than 0.2 m";
  EXPECT_GT(max_dev, 0.3) << "did not go around";
  EXPECT_LT((a.position_m - goal).norm(), 0.1) << "did not reach the goal";
}

INSTANTIATE_TEST_SUITE_P(Offsets, RobotInTheWay, ::testing::Values(0.0, 0.2, -0.2, 0.5));

// A person who does not notice the robot (notices_robot: false) keeps their
// line at full force until the bodies touch; the contact force still stops them.
TEST(SocialForce, APersonWhoDoesNotNoticeTheRobotKeepsTheirLineUntilContact) {
  const SocialForceParams p;
  Agent robot;
  robot.position_m = V(3, 0);
  robot.radius_m = 0.35;
  struct Pass {
    double min_d = 1e9, dev_before = 0.0;
  };
  auto pass = [&](bool notices) {
    Agent a = walker(V(0, 0.2), V(1, 0));
    a.notices_robot = notices;
    Pass r;
    for (int k = 0; k < 30000; ++k) {
      aimAt(a, V(8, 0.2));
      integrate(a, computeForce(a, {}, {}, &robot, p).total(), p, kDt_s);
      r.min_d = std::min(r.min_d, (a.position_m - robot.position_m).norm());
      if (a.position_m.x() < robot.position_m.x() - 1.0)
        r.dev_before = std::max(r.dev_before, std::abs(a.position_m.y() - 0.2));
    }
    return r;
  };
  const Pass noticing = pass(true), distracted = pass(false);
  EXPECT_GT(noticing.dev_before, 0.05) << "the reference walker did not give way early";
  EXPECT_LT(distracted.dev_before, 0.01) << "felt the robot from afar";
  EXPECT_LT(distracted.min_d, noticing.min_d - 0.1) << "kept a social distance";
  EXPECT_GT(distracted.min_d, 0.35 + 0.25 - 0.05) << "walked through the robot";
}

TEST(SocialForce, CoincidentAndDegenerateInputGiveFiniteForces) {
  const SocialForceParams p;
  // Two people on the same spot, same velocity and goal.
  std::vector<Agent> a{walker(V(1, 1), V(1, 0)), walker(V(1, 1), V(1, 0))};
  const auto f0 = computeForce(a[0], a, {}, nullptr, p);
  const auto f1 = computeForce(a[1], a, {}, nullptr, p);
  ASSERT_TRUE(finite(f0.total()));
  ASSERT_TRUE(finite(f1.total()));
  EXPECT_LT(f0.people_m_s2.dot(f1.people_m_s2), 0.0) << "pushed the same way: they would never separate";
  std::vector<V> scratch(2);
  for (int k = 0; k < 2000; ++k) stepAgents(a, {}, nullptr, p, kDt_s, scratch);
  EXPECT_TRUE(finite(a[0].position_m) && finite(a[1].position_m));
  EXPECT_GT((a[0].position_m - a[1].position_m).norm(), 0.5) << "still overlapping after 2 s";

  // On the robot's centre; on a wall; on a zero-length wall; standing still.
  Agent robot;
  robot.position_m = V(1, 1);
  robot.radius_m = 0.35;
  const std::vector<WallSegment> walls{wallOf(V(0, 1), V(2, 1)), wallOf(V(1, 1), V(1, 1))};
  Agent still;
  still.position_m = V(1, 1);
  const auto f = computeForce(still, {}, walls, &robot, p);
  EXPECT_TRUE(finite(f.total()));
  EXPECT_GT(f.robot_m_s2.norm(), 0.0);
  EXPECT_GT(f.walls_m_s2.norm(), 0.0);

  // Non-finite input: zero force, and integrate() leaves a finite state.
  Agent bad = walker(V(std::numeric_limits<double>::quiet_NaN(), 0), V(1, 0));
  EXPECT_EQ(computeForce(bad, {}, walls, &robot, p).total(), V::Zero());
  Agent ok = walker(V(0, 0), V(1, 0));
  integrate(ok, V(std::numeric_limits<double>::infinity(), 0), p, kDt_s);
  EXPECT_TRUE(finite(ok.position_m) && finite(ok.velocity_m_s));
}

TEST(SocialForce, PersonBehindPushesLessThanPersonAhead) {
  SocialForceParams p;
  p.sidestep = 0.0;
  p.contact.strength_m_s2 = 0.0;  // only the anisotropic social term
  const Agent self = walker(V(0, 0), V(1, 0));
  const Agent ahead = walker(V(1, 0), V(0, 1));
  const Agent behind = walker(V(-1, 0), V(0, 1));
  const Agent beside = walker(V(0, 1), V(0, 1));
  const double fa = computeForce(self, std::vector<Agent>{ahead}, {}, nullptr, p).people_m_s2.norm();
  const double fb = computeForce(self, std::vector<Agent>{behind}, {}, nullptr, p).people_m_s2.norm();
  const double fs = computeForce(self, std::vector<Agent>{beside}, {}, nullptr, p).people_m_s2.norm();
  EXPECT_GT(fa, fb);
  EXPECT_NEAR(fb / fa, p.people.anisotropy, 1e-12);              // w(pi) = lambda
  EXPECT_NEAR(fs / fa, (1 + p.people.anisotropy) / 2.0, 1e-12);  // w(pi/2)
  EXPECT_NEAR(fa, p.people.strength_m_s2 * std::exp((0.5 - 1.0) / p.people.range_m), 1e-12);
}

struct WeightCase {
  double lambda, phi_rad, expect;
};

class Anisotropy : public ::testing::TestWithParam<WeightCase> {};

TEST_P(Anisotropy, WeightOfDirection) {
  const auto c = GetParam();
  const V heading(2.0, 0.0);  // need not be unit length
  const V to_source(std::cos(c.phi_rad), std::sin(c.phi_rad));
  EXPECT_NEAR(anisotropyWeight(c.lambda, heading, to_source), c.expect, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Table, Anisotropy,
                         ::testing::Values(WeightCase{0.35, 0.0, 1.0}, WeightCase{0.35, std::numbers::pi, 0.35},
                                           WeightCase{0.35, std::numbers::pi / 2, 0.675},
                                           WeightCase{0.35, -std::numbers::pi / 2, 0.675},
                                           WeightCase{1.0, std::numbers::pi, 1.0},
                                           WeightCase{0.0, std::numbers::pi, 0.0},
                                           WeightCase{0.0, std::numbers::pi / 3, 0.75}));

TEST(SocialForce, AnisotropyIsOneWithoutAHeading) {
  EXPECT_EQ(anisotropyWeight(0.2, V::Zero(), V(1, 0)), 1.0);
  EXPECT_EQ(anisotropyWeight(0.2, V(1, 0), V::Zero()), 1.0);
}

// --- prediction (what the robot will use) ---

TEST(PredictPath, FreeWalkerKeepsVelocity) {
  const SocialForceParams p;
  Agent person;
  person.position_m = V(1, 2);
  person.velocity_m_s = V(0.3, -0.4);  // 0.5 m/s
  person.desired_speed_m_s = 1.0;      // ignored: the current speed is assumed
  const auto path = predictPath(person, nullptr, {}, p, 3.0, 0.1);
  ASSERT_EQ(path.size(), 30u);
  for (std::size_t k = 0; k < path.size(); ++k) {
    const double t = 0.1 * static_cast<double>(k + 1);
    EXPECT_NEAR(path[k].x(), 1 + 0.3 * t, 1e-9) << k;
    EXPECT_NEAR(path[k].y(), 2 - 0.4 * t, 1e-9) << k;
  }
}

TEST(PredictPath, StandingPersonStaysAndBadStepGivesNothing) {
  const SocialForceParams p;
  Agent person;
  person.position_m = V(1, 2);
  person.velocity_m_s = V(0.01, 0.0);
  const auto path = predictPath(person, nullptr, {}, p, 1.0, 0.1);
  ASSERT_EQ(path.size(), 10u);
  for (const auto& q : path) EXPECT_EQ(q, V(1, 2));
  EXPECT_TRUE(predictPath(person, nullptr, {}, p, 1.0, 0.0).empty());
  EXPECT_TRUE(predictPath(person, nullptr, {}, p, 1.0, std::numeric_limits<double>::quiet_NaN()).empty());
  EXPECT_TRUE(predictPath(person, nullptr, {}, p, -1.0, 0.1).empty());
}

TEST(PredictPath, PersonHeadingForTheRobotIsPredictedToGoAround) {
  const SocialForceParams p;
  Agent robot;  // driving +x at 0.5 m/s from the origin
  robot.radius_m = 0.35;
  robot.velocity_m_s = V(0.5, 0.0);
  Agent person;  // 5.5 m ahead, walking at it
  person.position_m = V(5.5, 0.0);
  person.velocity_m_s = V(-0.5, 0.0);
  const std::vector<WallSegment> walls{wallOf(V(-5, -1.5), V(15, -1.5)), wallOf(V(-5, 1.5), V(15, 1.5))};
  std::array<V, 100> out;  // 10 s at 0.1 s, caller-owned: no allocation
  ASSERT_EQ(predictPath(person, &robot, walls, p, 0.1, out), out.size());
  double min_d = 1e9;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const V robot_at = robot.velocity_m_s * 0.1 * static_cast<double>(k + 1);
    min_d = std::min(min_d, (out[k] - robot_at).norm());
    EXPECT_LT(std::abs(out[k].y()), 1.5 - 0.25) << "predicted through a wall at step " << k;
  }
  EXPECT_GT(min_d, 0.6) << "predicted to walk through the robot";
  EXPECT_LT(out.back().x(), 5.0 - 2.0) << "predicted to get past the robot (at x = 5 m by then)";
  EXPECT_GT(out[60].y(), 0.5) << "predicted to step to its right (+y, walking -x)";
}

// --- Eq 8 ---

struct AvoidCase {
  double r_avoid_m, v_m_s, t_s, expect_m;
};

class AvoidanceDistance : public ::testing::TestWithParam<AvoidCase> {};

TEST_P(AvoidanceDistance, Eq8) {
  const auto c = GetParam();
  EXPECT_NEAR(avoidanceDistance(c.r_avoid_m, c.v_m_s, c.t_s), c.expect_m, 1e-12)
      << c.r_avoid_m << " " << c.v_m_s << " " << c.t_s;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

INSTANTIATE_TEST_SUITE_P(Table, AvoidanceDistance,
                         ::testing::Values(AvoidCase{3.0, 0.5, 1.0, 2.5},    // R - v t
                                           AvoidCase{3.0, 0.5, 0.0, 3.0},    // t = 0: the full distance
                                           AvoidCase{1.5, 0.0, 5.0, 1.5},    // standing robot covers nothing
                                           AvoidCase{3.0, 0.5, 4.0, 1.0},    //
                                           AvoidCase{3.0, 0.5, 6.0, 0.0},    // exactly used up
                                           AvoidCase{3.0, 0.5, 10.0, 0.0},   // clamped at 0
                                           AvoidCase{3.0, -0.5, 1.0, 3.0},   // reversing: never above R
                                           AvoidCase{3.0, kNaN, 1.0, 3.0},   // unknown speed: keep the full distance
                                           AvoidCase{3.0, 0.5, kInf, 0.0},   //
                                           AvoidCase{-1.0, 0.5, 1.0, 0.0},   // nonsense R
                                           AvoidCase{kNaN, 0.5, 1.0, 0.0}));

// --- configuration ---

TEST(SocialForceParams, ReadWithDefaultsAndErrorsNamingFileAndKey) {
  using inspect::config::ConfigError;
  using inspect::config::ConfigNode;
  const auto root = ConfigNode::loadString("social_force:\n  relaxation_time_s: 0.4\n  people: {range_m: 0.3}\n",
                                           "sf.yaml");
  const auto p = readSocialForceParams(root.optChild("social_force"));
  root.checkKnown();
  EXPECT_DOUBLE_EQ(p.relaxation_time_s, 0.4);
  EXPECT_DOUBLE_EQ(p.people.range_m, 0.3);
  EXPECT_DOUBLE_EQ(p.people.strength_m_s2, SocialForceParams{}.people.strength_m_s2);
  EXPECT_DOUBLE_EQ(p.robot.range_m, SocialForceParams{}.robot.range_m);

  const auto bad = ConfigNode::loadString("social_force:\n  people: {range_m: 0}\n", "sf.yaml");
  try {
    (void)readSocialForceParams(bad.optChild("social_force"));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sf.yaml: social_force.people.range_m"), std::string::npos) << e.what();
  }
}
