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
