// The `pedestrians:` and `social_force:` sections of world files: parsing,
// defaults, errors naming file and key, and the shipped scenario worlds.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "shared/world/world.hpp"
#include "tests/sim/world_text.hpp"
#include "tests/support/paths.hpp"

using namespace inspect::sim;
using namespace inspect::world;
using inspect::config::ConfigError;
using inspect::config::ConfigNode;

namespace {

using inspect::test::worldOf;


std::string errorOf(const std::string& yaml) { return inspect::test::worldError(yaml, "peds.yaml"); }

double dist(Vec2 a, Vec2 b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

TEST(PedestrianWorld, FullEntryParses) {
  const World w = worldOf(R"(
pedestrians:
  - id: alice
    radius_m: 0.3
    speed_m_s: 1.2
    start_s: 2.5
    route_m: [0, 0,  4, 0,  4, 3]
    pauses: [{at: 1, s: 2.0}, {at: 0, s: 0.5}]
    loop: true
    arrive_m: 0.2
social_force:
  relaxation_time_s: 0.6
  max_speed_factor: 1.5
  sidestep: 0.2
  people: {strength_m_s2: 1.5, range_m: 0.4, anisotropy: 0.5}
  walls: {strength_m_s2: 4.0}
  robot: {range_m: 0.8}
  contact: {strength_m_s2: 20.0, range_m: 0.1}
)", "peds.yaml");
  ASSERT_EQ(w.pedestrians.size(), 1u);
  const auto& p = w.pedestrians[0];
  EXPECT_EQ(p.id, "alice");
  EXPECT_DOUBLE_EQ(p.radius_m, 0.3);
  EXPECT_DOUBLE_EQ(p.speed_m_s, 1.2);
  EXPECT_DOUBLE_EQ(p.start_s, 2.5);
  ASSERT_EQ(p.route.size(), 3u);
  EXPECT_DOUBLE_EQ(p.route[2].x, 4.0);
  EXPECT_DOUBLE_EQ(p.route[2].y, 3.0);
  ASSERT_EQ(p.pauses.size(), 2u);
  EXPECT_EQ(p.pauses[0].at, 1u);
  EXPECT_DOUBLE_EQ(p.pauses[0].duration_s, 2.0);
  EXPECT_TRUE(p.loop);
  EXPECT_DOUBLE_EQ(p.arrive_m, 0.2);
  EXPECT_DOUBLE_EQ(w.social_force.relaxation_time_s, 0.6);
  EXPECT_DOUBLE_EQ(w.social_force.max_speed_factor, 1.5);
  EXPECT_DOUBLE_EQ(w.social_force.sidestep, 0.2);
  EXPECT_DOUBLE_EQ(w.social_force.people.anisotropy, 0.5);
  EXPECT_DOUBLE_EQ(w.social_force.walls.strength_m_s2, 4.0);
  EXPECT_DOUBLE_EQ(w.social_force.robot.range_m, 0.8);
  EXPECT_DOUBLE_EQ(w.social_force.contact.range_m, 0.1);
}

TEST(PedestrianWorld, Defaults) {
  const World w = worldOf("pedestrians:\n  - {route_m: [1, 2]}\n  - {route_m: [3, 4, 5, 6]}\n", "peds.yaml");
  ASSERT_EQ(w.pedestrians.size(), 2u);
  const auto& p = w.pedestrians[0];
  EXPECT_EQ(p.id, "person0");
  EXPECT_EQ(w.pedestrians[1].id, "person1");
  EXPECT_DOUBLE_EQ(p.radius_m, 0.25);
  EXPECT_DOUBLE_EQ(p.speed_m_s, 0.5);
  EXPECT_DOUBLE_EQ(p.start_s, 0.0);
  EXPECT_DOUBLE_EQ(p.arrive_m, 0.3);
  EXPECT_FALSE(p.loop);
  EXPECT_TRUE(p.pauses.empty());
  // No social_force section: the model's defaults.
  const inspect::behavior::SocialForceParams d;
  EXPECT_DOUBLE_EQ(w.social_force.relaxation_time_s, d.relaxation_time_s);
  EXPECT_DOUBLE_EQ(w.social_force.people.strength_m_s2, d.people.strength_m_s2);
  EXPECT_TRUE(worldOf("name: x\n", "peds.yaml").pedestrians.empty());
}

TEST(PedestrianWorld, BadValuesNameFileKeyAndReason) {
  struct Case {
    const char* yaml;
    const char* key;
    const char* reason;
  };
  const Case cases[] = {
      {"pedestrians:\n  - {route_m: [0, 0], radius_m: 0}\n", "pedestrians[0].radius_m", "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0], speed_m_s: -0.5}\n", "pedestrians[0].speed_m_s", "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0], start_s: -1}\n", "pedestrians[0].start_s", "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0], arrive_m: 0}\n", "pedestrians[0].arrive_m", "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0], loop: maybe}\n", "pedestrians[0].loop", "not true or false"},
      {"pedestrians:\n  - {id: a}\n", "pedestrians[0].route_m", "missing"},
      {"pedestrians:\n  - {route_m: []}\n", "pedestrians[0].route_m", "at least 1 point"},
      {"pedestrians:\n  - {route_m: [0, 0, 1]}\n", "pedestrians[0].route_m", "even count"},
      {"pedestrians:\n  - {route_m: [0, 0, 2000, 0]}\n", "pedestrians[0].route_m", "[-1000, 1000]"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 1, 1, 1]}\n", "pedestrians[0].route_m", "points 1 and 2 are the same"},
      {"pedestrians:\n  - {route_m: [0, 0, x, 1]}\n", "pedestrians[0].route_m", "not a number"},
      {"walls:\n  - {from_m: [-5, 0.1], to_m: [5, 0.1]}\npedestrians:\n  - {route_m: [0, 0]}\n",
       "pedestrians[0].route_m", "point 0 (0, 0) is closer than radius_m"},
      {"obstacles:\n  - {vertices_m: [2, -1, 3, -1, 3, 1, 2, 1]}\npedestrians:\n  - {route_m: [0, 0, 2.5, 0]}\n",
       "pedestrians[0].route_m", "point 1 (2.5, 0)"},
      {"pedestrians:\n  - {route_m: [0, 0], loop: true}\n", "pedestrians[0].loop", "at least 2 points"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 2, s: 1}]}\n", "pedestrians[0].pauses[0].at",
       "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 0.5, s: 1}]}\n", "pedestrians[0].pauses[0].at",
       "not a whole number"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{s: 1}]}\n", "pedestrians[0].pauses[0].at", "missing"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 1}]}\n", "pedestrians[0].pauses[0].s", "missing"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 1, s: 0}]}\n", "pedestrians[0].pauses[0].s",
       "out of range"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 1, s: 1}, {at: 1, s: 2}]}\n",
       "pedestrians[0].pauses[1].at", "already has a pause"},
      {"pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: 3}\n", "pedestrians[0].pauses", "must be a list"},
      {"pedestrians:\n  - {id: 'a,b', route_m: [0, 0]}\n", "pedestrians[0].id", "letters, digits"},
      {"pedestrians:\n  - {id: '', route_m: [0, 0]}\n", "pedestrians[0].id", "letters, digits"},
      {"pedestrians:\n  - {id: a, route_m: [0, 0]}\n  - {id: a, route_m: [5, 5]}\n", "pedestrians[1].id",
       "already used by pedestrians[0]"},
      {"pedestrians: {id: a}\n", "pedestrians", "must be a list"},
      {"social_force:\n  relaxation_time_s: 0\n", "social_force.relaxation_time_s", "out of range"},
      {"social_force:\n  max_speed_factor: 0.5\n", "social_force.max_speed_factor", "out of range"},
      {"social_force:\n  people: {anisotropy: 1.5}\n", "social_force.people.anisotropy", "out of range"},
      {"social_force:\n  walls: {strength_m_s2: -1}\n", "social_force.walls.strength_m_s2", "out of range"},
      {"social_force:\n  sidestep: 2\n", "social_force.sidestep", "out of range"},
  };
  for (const auto& c : cases) {
    const auto e = errorOf(c.yaml);
    EXPECT_NE(e.find(std::string("peds.yaml: ") + c.key), std::string::npos) << c.yaml << " -> " << e;
    EXPECT_NE(e.find(c.reason), std::string::npos) << c.yaml << " -> " << e;
  }
}

TEST(PedestrianWorld, UnknownKeysRejected) {
  const auto e = errorOf("pedestrians:\n  - {route_m: [0, 0], spead_m_s: 1}\n");
  EXPECT_NE(e.find("peds.yaml: pedestrians[0].spead_m_s: unknown key"), std::string::npos) << e;
  const auto t = errorOf("pedestrians:\n  - {route_m: [0, 0], time_scale: 2}\n");
  EXPECT_NE(t.find("pedestrians[0].time_scale: unknown key"), std::string::npos) << t;
  const auto p = errorOf("pedestrians:\n  - {route_m: [0, 0, 1, 0], pauses: [{at: 1, s: 1, for_s: 2}]}\n");
  EXPECT_NE(p.find("pedestrians[0].pauses[0].for_s: unknown key"), std::string::npos) << p;
  const auto s = errorOf("social_force:\n  people: {A: 2}\n");
  EXPECT_NE(s.find("social_force.people.A: unknown key"), std::string::npos) << s;
}

TEST(PedestrianWorld, ShippedCrossingLoads) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/crossing.yaml"));
  EXPECT_EQ(w.name, "crossing");
  EXPECT_NO_THROW(checkStartPose(w, 0.35));
  EXPECT_DOUBLE_EQ(w.start.x_m, 0.0);
  EXPECT_DOUBLE_EQ(w.start.theta_rad, 0.0);
  ASSERT_EQ(w.pedestrians.size(), 1u);
  const auto& p = w.pedestrians[0];
  EXPECT_DOUBLE_EQ(p.speed_m_s, 0.5);
  ASSERT_GE(p.route.size(), 2u);
  const Vec2 a = p.route.front(), b = p.route.back();
  // Front-left to front-right, crossing the robot's line y = 0 3..4.5 m ahead.
  EXPECT_GT(a.x, 0.0);
  EXPECT_GT(a.y, 1.0);
  EXPECT_LT(b.y, -1.0);
  const double x_cross = a.x + (b.x - a.x) * a.y / (a.y - b.y);
  EXPECT_GT(x_cross, 3.0);
  EXPECT_LT(x_cross, 4.5);
  EXPECT_NEAR(dist(a, {0, 0}), 5.5, 0.2);
  // Aisles 2.5-3 m wide: the robot's aisle across y, the cross aisle across x at the crossing.
  EXPECT_GT(clearance(w, {0.0, 0.0}), 1.25);
  EXPECT_LT(clearance(w, {0.0, 0.0}), 1.5);
  EXPECT_GT(clearance(w, {x_cross, 4.0}), 1.25);
  EXPECT_LT(clearance(w, {x_cross, 4.0}), 1.5);
  // The straight 0.5 m/s runs of both reach the crossing within ~1 s of each other.
  const double t_person = std::abs(a.y) / p.speed_m_s;
  const double t_robot = x_cross / 0.5;
  EXPECT_NEAR(t_person, t_robot, 1.0);
}

TEST(PedestrianWorld, ShippedEncounteringLoads) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/encountering.yaml"));
  EXPECT_EQ(w.name, "encountering");
  EXPECT_NO_THROW(checkStartPose(w, 0.35));
  ASSERT_EQ(w.pedestrians.size(), 1u);
  const auto& p = w.pedestrians[0];
  EXPECT_DOUBLE_EQ(p.speed_m_s, 0.5);
  const Vec2 a = p.route.front(), b = p.route.back();
  EXPECT_NEAR(dist(a, {0, 0}), 5.5, 0.2);
  EXPECT_NEAR(a.y, 0.6, 1e-9);  // lateral offset
  EXPECT_NEAR(b.y, 0.6, 1e-9);
  EXPECT_LT(b.x, 0.0);          // walks towards and past the robot
  // A ~3 m wide aisle.
  const double width = clearance(w, {0.0, 0.0}) * 2;
  EXPECT_NEAR(width, 3.0, 0.3);
}

TEST(PedestrianWorld, SolidEdgesMarkSharedCorners) {
  const World w = worldOf(
      "walls:\n  - {points_m: [0, 0, 4, 0, 4, 3]}\n  - {from_m: [10, 0], to_m: [11, 0]}\n"
      "obstacles:\n  - {vertices_m: [5, 5, 6, 5, 6, 6]}\n", "peds.yaml");
  const auto e = solidEdges(w);
  ASSERT_EQ(e.size(), 2u + 1u + 3u);
  // Polyline: the free ends are not joined, the bend is.
  EXPECT_FALSE(e[0].a_joined);
  EXPECT_TRUE(e[0].b_joined);
  EXPECT_TRUE(e[1].a_joined);
  EXPECT_FALSE(e[1].b_joined);
  // A lone segment: nothing joined.
  EXPECT_FALSE(e[2].a_joined || e[2].b_joined);
  // A polygon: every corner joined.
  for (std::size_t i = 3; i < 6; ++i) EXPECT_TRUE(e[i].a_joined && e[i].b_joined) << i;
}
