// The people tracker's steps one at a time (HumanTracker::step calls them in
// this order; test_human_tracker.cpp tests them together).
#include <gtest/gtest.h>

#include <cmath>

#include "shared/behavior/human_tracker.hpp"
#include "tests/shared/behavior/sonar_echoes.hpp"

using namespace inspect;
using behavior::HumanTracker;
using behavior::SonarEchoes;

namespace {
const control::Pose2 kOrigin{0, 0, 0};
constexpr double kNoEcho = -1.0;
}  // namespace

TEST(TrackerSteps, EchoOfIgnoresNoRangeAndTheMapsWallsAndPlacesTheRestOnTheBeam) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {}, {{{3.0, -2.0}, {3.0, 2.0}}});  // a wall 3 m ahead
  EXPECT_FALSE(tr.echoOf(0, kOrigin, kNoEcho, 0.0));
  EXPECT_FALSE(tr.echoOf(0, kOrigin, u.max_range_m, 0.0)) << "at max range: nothing heard";
  EXPECT_EQ(tr.counters().echoes, 0u);
  const control::Pose2 s0 = config::mountPose(kOrigin, u.mounts[0]);
  EXPECT_FALSE(tr.echoOf(0, kOrigin, 3.0 - s0.x_m, 0.0)) << "the map's wall";
  EXPECT_EQ(tr.counters().static_map, 1u);
  const auto e = tr.echoOf(0, kOrigin, 1.5, 0.0);
  ASSERT_TRUE(e);
  EXPECT_TRUE(e->use);
  EXPECT_NEAR(e->z.x(), s0.x_m + 1.5 * std::cos(s0.theta_rad), 1e-9);
  EXPECT_NEAR(e->z.y(), s0.y_m + 1.5 * std::sin(s0.theta_rad), 1e-9);
  EXPECT_NEAR(e->yaw, s0.theta_rad, 1e-12);
  EXPECT_GT(e->r(0, 0), 0.0);
  EXPECT_TRUE(tr.tracks().empty()) << "a point, not yet a track";
}

TEST(TrackerSteps, TheFrontPairFixesTheBearingAndALoneFrontEchoMovesOutward) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  // A person 2 m ahead, 0.3 m to the left: both front sensors hear them.
  const auto ranges = test::echoes(u, kOrigin, {{2.0, 0.3, 0.25}}, {});
  ASSERT_GT(ranges[0], 0.0);
  ASSERT_GT(ranges[1], 0.0);
  SonarEchoes echo{};
  for (std::size_t i = 0; i < 2; ++i) echo[i] = *tr.echoOf(i, kOrigin, ranges[i], 0.0);
  tr.placeLoneFrontEcho(kOrigin, ranges, echo);  // both heard: nothing to do
  tr.triangulateFrontPair(kOrigin, echo);
  EXPECT_TRUE(echo[0].use);
  EXPECT_FALSE(echo[1].use) << "the fused point replaces both";
  EXPECT_EQ(tr.counters().triangulated, 1u);
  EXPECT_GT(echo[0].z.y(), 0.1) << "on the person's side of the centre line";
  // One front sensor alone: its point moves to its outer half.
  HumanTracker lone(u, {});
  SonarEchoes one{};
  const std::size_t i = u.mounts[0].y_m > u.mounts[1].y_m ? 0 : 1;  // the left sensor
  one[i] = *lone.echoOf(i, kOrigin, 2.0, 0.0);
  const double y_before = one[i].z.y();
  std::array<double, 4> r{kNoEcho, kNoEcho, kNoEcho, kNoEcho};
  r[i] = 2.0;
  lone.placeLoneFrontEcho(kOrigin, r, one);
  EXPECT_GT(one[i].z.y(), y_before) << "the left sensor's echo moves left";
}

TEST(TrackerSteps, AssociateStartsATrackThenFeedsIt) {
  const config::UltrasonicConfig u;
  HumanTracker tr(u, {});
  std::array<double, 4> r{2.0, kNoEcho, kNoEcho, kNoEcho};
  SonarEchoes echo{};
  echo[0] = *tr.echoOf(0, kOrigin, 2.0, 0.0);
  tr.associate(0, kOrigin, r, echo, 0.0);
  ASSERT_EQ(tr.tracks().size(), 1u);
  EXPECT_EQ(tr.tracks()[0].hits, 1);
  EXPECT_EQ(tr.counters().tracks_created, 1u);
  echo[0] = *tr.echoOf(0, kOrigin, 2.05, 0.1);
  tr.associate(0, kOrigin, r, echo, 0.1);
  ASSERT_EQ(tr.tracks().size(), 1u) << "within the gate: the same track";
  EXPECT_EQ(tr.tracks()[0].hits, 2);
  EXPECT_EQ(tr.counters().associated, 1u);
}

TEST(TrackerSteps, ConfirmedByHitsContradictedBySilenceThenDropped) {
  const config::UltrasonicConfig u;
  behavior::HumanTrackerParams p;
  HumanTracker tr(u, p);
  std::array<double, 4> r{2.0, kNoEcho, kNoEcho, kNoEcho};
  SonarEchoes echo{};
  for (int k = 0; k < p.confirm_hits; ++k) {
    echo[0] = *tr.echoOf(0, kOrigin, 2.0, 0.01 * k);
    tr.associate(0, kOrigin, r, echo, 0.01 * k);
  }
  tr.classifyTracks(0.05);
  ASSERT_EQ(tr.tracks().size(), 1u);
  EXPECT_TRUE(tr.tracks()[0].confirmed);
  EXPECT_FALSE(tr.tracks()[0].person) << "standing still: not yet a person";
  // The sensor that heard it now hears nothing there.
  const std::array<double, 4> silent{kNoEcho, kNoEcho, kNoEcho, kNoEcho};
  for (int k = 1; k < p.contradiction_ticks; ++k) {
    tr.markContradicted(kOrigin, silent, 0.05 + 0.01 * k);
    tr.dropTracks(0.05 + 0.01 * k);
    ASSERT_EQ(tr.tracks().size(), 1u) << "tick " << k;
    EXPECT_EQ(tr.tracks()[0].contradicted, k);
  }
  tr.markContradicted(kOrigin, silent, 0.2);
  tr.dropTracks(0.2);
  EXPECT_TRUE(tr.tracks().empty());
  EXPECT_EQ(tr.counters().tracks_contradicted, 1u);
}
