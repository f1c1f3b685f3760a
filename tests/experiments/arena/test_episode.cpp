// The arena's episodes (experiments/arena/episode): reproducible from their
// seed, printable as a world file that reads back to the same world, and
// covering the ranges the arena promises (layouts, widths, 1-3 people,
// speeds, crossing angles, every behaviour).
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "experiments/arena/episode.hpp"
#include "shared/world/world.hpp"

using namespace inspect;
using arena::Behaviour;

TEST(ArenaEpisode, SameSeedSameEpisodeOtherSeedOther) {
  const auto a = arena::generateEpisode(7, 12), b = arena::generateEpisode(7, 12);
  EXPECT_EQ(arena::worldYaml(a), arena::worldYaml(b));
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_NE(arena::worldYaml(a), arena::worldYaml(arena::generateEpisode(7, 13)));
  EXPECT_NE(arena::worldYaml(a), arena::worldYaml(arena::generateEpisode(8, 12)));
}

TEST(ArenaEpisode, WorldFileReadsBackToTheSameWorld) {
  for (int k = 0; k < 20; ++k) {
    const auto e = arena::generateEpisode(1, k);
    const auto w = world::loadWorldText(arena::worldYaml(e), "printed");
    ASSERT_EQ(w.pedestrians.size(), e.spec.world.pedestrians.size()) << k;
    ASSERT_EQ(w.walls.size(), e.spec.world.walls.size()) << k;
    for (std::size_t i = 0; i < w.pedestrians.size(); ++i) {
      EXPECT_EQ(w.pedestrians[i].route.size(), e.spec.world.pedestrians[i].route.size());
      EXPECT_EQ(w.pedestrians[i].notices_robot, e.spec.world.pedestrians[i].notices_robot);
      EXPECT_DOUBLE_EQ(w.pedestrians[i].speed_m_s, e.spec.world.pedestrians[i].speed_m_s);
    }
  }
}

TEST(ArenaEpisode, FiveHundredEpisodesCoverTheRanges) {
  std::set<double> widths;
  std::set<int> counts;
  std::set<Behaviour> behaviours;
  int aisles = 0, crossings = 0;
  double min_speed = 10, max_speed = 0, min_angle = 180, max_angle = 0;
  for (int k = 0; k < 500; ++k) {
    const auto e = arena::generateEpisode(1, k);  // throws if any generated world were invalid
    (e.layout == arena::Layout::kAisle ? aisles : crossings) += 1;
    widths.insert(e.width_m);
    counts.insert(static_cast<int>(e.people.size()));
    ASSERT_GE(e.people.size(), 1u);
    ASSERT_LE(e.people.size(), 3u);
    for (const auto& p : e.people) {
      behaviours.insert(p.behaviour);
      min_speed = std::min(min_speed, p.speed_m_s);
      max_speed = std::max(max_speed, p.speed_m_s);
      if (e.layout == arena::Layout::kCrossing && p.heading_deg > 1 && p.heading_deg < 179) {
        min_angle = std::min(min_angle, p.heading_deg);
        max_angle = std::max(max_angle, p.heading_deg);
      }
    }
    for (std::size_t i = 0; i < e.people.size(); ++i)
      EXPECT_EQ(e.spec.world.pedestrians[i].notices_robot, e.people[i].behaviour != Behaviour::kNotReacting);
  }
  EXPECT_GT(aisles, 150);
  EXPECT_GT(crossings, 150);
  EXPECT_EQ(widths.size(), 4u);
  EXPECT_EQ(counts, (std::set<int>{1, 2, 3}));
  EXPECT_EQ(behaviours.size(), 4u);
  EXPECT_LT(min_speed, 0.35);
  EXPECT_GT(max_speed, 1.55);
  EXPECT_LT(min_angle, 35);
  EXPECT_GT(max_angle, 145);
}

TEST(ArenaEpisode, TogetherIsTwoPeopleSideBySide) {
  for (int k = 0; k < 200; ++k) {
    const auto e = arena::generateEpisode(3, k);
    for (std::size_t i = 0; i + 1 < e.people.size(); ++i) {
      if (e.people[i].behaviour != Behaviour::kTogether) continue;
      ASSERT_EQ(e.people[i + 1].behaviour, Behaviour::kTogether);
      const auto& a = e.spec.world.pedestrians[i].route.front();
      const auto& b = e.spec.world.pedestrians[i + 1].route.front();
      EXPECT_NEAR(std::hypot(a.x - b.x, a.y - b.y), 0.7, 1e-3);
      EXPECT_EQ(e.spec.world.pedestrians[i].start_s, e.spec.world.pedestrians[i + 1].start_s);
      ++i;
    }
  }
}

// social_arena --crossings: eight distinct cases, each one person crossing
// the robot's path at its angle and speed, yielding or not, timed to reach
// the crossing point (5, 0) when the robot would (1 s + 5 m / 0.5 m/s).
TEST(ArenaEpisode, CrossingCasesCrossThePathAtTheirAngleWhenTheRobotArrives) {
  const auto cases = arena::crossingCases();
  ASSERT_EQ(cases.size(), 8u);
  std::set<std::string> names;
  for (const auto& c : cases) {
    names.insert(c.name());
    const auto e = arena::crossingEpisode(c);
    ASSERT_EQ(e.spec.world.pedestrians.size(), 1u) << c.name();
    const auto& p = e.spec.world.pedestrians[0];
    EXPECT_DOUBLE_EQ(p.speed_m_s, c.speed_m_s);
    EXPECT_EQ(p.notices_robot, c.yields) << c.name();
    ASSERT_EQ(p.route.size(), 2u);
    const auto a = p.route[0], b = p.route[1];
    EXPECT_NEAR(std::atan2(b.y - a.y, b.x - a.x) * 180 / M_PI, c.angle_deg, 1e-6) << c.name();
    EXPECT_LT(a.y, -1.5) << "starts outside the robot's aisle: " << c.name();
    EXPECT_GT(b.y, 1.5) << c.name();
    // Where the route meets y = 0, and when.
    const double s = -a.y / (b.y - a.y);
    EXPECT_NEAR(a.x + s * (b.x - a.x), 5.0, 1e-3) << c.name();
    const double walk = s * std::hypot(b.x - a.x, b.y - a.y);
    const double arrive = p.start_s + walk / c.speed_m_s;
    EXPECT_NEAR(arrive, 11.0, 0.01) << c.name();
    EXPECT_EQ(arena::worldYaml(e), arena::worldYaml(arena::crossingEpisode(c)));
  }
  EXPECT_EQ(names.size(), 8u);
  EXPECT_EQ(names.count("cross135_slow_does_not_yield"), 1u);
}
