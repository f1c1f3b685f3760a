// World files and geometry: shipped worlds load, errors name file and key,
// ray casting and clearance against segments, convex and concave polygons.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>

#include "shared/world/world.hpp"
#include "tests/sim/world_text.hpp"
#include "tests/support/paths.hpp"

using namespace inspect::world;
using inspect::config::ConfigError;
using inspect::config::ConfigNode;

namespace {

using inspect::test::worldOf;


std::string errorOf(const std::string& yaml) { return inspect::test::worldError(yaml, "test_world.yaml"); }

}  // namespace

TEST(WorldFile, ShippedSquareRoomLoads) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/square_room.yaml"));
  EXPECT_EQ(w.name, "square_room");
  EXPECT_EQ(w.walls.size(), 4u);  // closed polyline of 4 points
  ASSERT_EQ(w.obstacles.size(), 1u);
  EXPECT_EQ(w.obstacles[0].name, "box");
  EXPECT_EQ(w.floor_lines.size(), 2u);
  // A 2 m x 2 m teleop square from the start pose stays clear of everything
  // (robot body radius 0.35 m), turning left or right.
  for (double x = 2.0; x <= 4.0; x += 0.1)
    for (double y = 2.0; y <= 6.0; y += 0.1) EXPECT_GT(clearance(w, {x, y}), 0.5) << x << "," << y;
  EXPECT_NO_THROW(checkStartPose(w, 0.35));
}

TEST(WorldFile, ShippedEmptyLoads) {
  const World w = loadWorldFile(inspect::test::srcPath("config/worlds/empty.yaml"));
  EXPECT_EQ(w.name, "empty");
  EXPECT_TRUE(w.walls.empty());
  EXPECT_TRUE(w.obstacles.empty());
  EXPECT_EQ(clearance(w, {0, 0}), std::numeric_limits<double>::infinity());
  EXPECT_FALSE(castRay(w, {0, 0}, 0.0, 100.0));
}

TEST(WorldFile, NameDefaultsToFileStemAndStartWraps) {
  const auto root = ConfigNode::loadString("start: {theta_rad: 6.0}\n", "/x/my_hall.yaml");
  const World w = loadWorld(root);
  EXPECT_EQ(w.name, "my_hall");
  EXPECT_NEAR(w.start.theta_rad, 6.0 - 2 * std::numbers::pi, 1e-12);
}

TEST(WorldFile, BadValueNamesFileAndKey) {
  const auto e = errorOf("start: {x_m: 5000}\n");
  EXPECT_NE(e.find("test_world.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("start.x_m"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

TEST(WorldFile, UnknownKeyRejected) {
  const auto e = errorOf("walls:\n  - {from_m: [0, 0], to_m: [1, 0], thickness_m: 0.1}\n");
  EXPECT_NE(e.find("test_world.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("walls[0].thickness_m: unknown key"), std::string::npos) << e;
  const auto top = errorOf("pedestrains: []\n");
  EXPECT_NE(top.find("pedestrains: unknown key"), std::string::npos) << top;
}

TEST(WorldFile, MalformedGeometryIsNamed) {
  struct Case {
    const char* yaml;
    const char* key;
    const char* reason;
  };
  const Case cases[] = {
      {"obstacles:\n  - {vertices_m: [0, 0, 1, 0, 1]}\n", "obstacles[0].vertices_m", "even count"},
      {"obstacles:\n  - {vertices_m: [0, 0, 1, 0]}\n", "obstacles[0].vertices_m", "at least 3"},
      {"obstacles:\n  - {vertices_m: [0, 0, 1, 0, 2, 0]}\n", "obstacles[0].vertices_m", "degenerate"},
      {"obstacles:\n  - {vertices_m: [0, 0, 2, 2, 2, 0, 0, 1]}\n", "obstacles[0].vertices_m", "simple polygon"},
      {"obstacles:\n  - {vertices_m: [0, 0, x, 0, 1, 1]}\n", "obstacles[0].vertices_m", "not a number"},
      {"walls:\n  - {from_m: [0, 0]}\n", "walls[0].to_m", "missing"},
      {"walls:\n  - {from_m: [0, 0], to_m: [0, 0]}\n", "walls[0].to_m", "zero length"},
      {"walls:\n  - {}\n", "walls[0].from_m", "required"},
      {"walls:\n  - {from_m: [0, 0], to_m: [1, 0], points_m: [0, 0, 1, 1]}\n", "walls[0].points_m", "not both"},
      {"walls: 3\n", "walls", "must be a list"},
      {"floor_lines:\n  - {from_m: [0, 0], to_m: [1, 0], width_m: 0}\n", "floor_lines[0].width_m", "out of range"},
  };
  for (const auto& c : cases) {
    const auto e = errorOf(c.yaml);
    EXPECT_NE(e.find(std::string("test_world.yaml: ") + c.key), std::string::npos) << c.yaml << " -> " << e;
    EXPECT_NE(e.find(c.reason), std::string::npos) << c.yaml << " -> " << e;
  }
}

TEST(WorldFile, MissingFileIsAConfigError) {
  EXPECT_THROW((void)loadWorldFile("/nonexistent/world.yaml"), ConfigError);
}

TEST(WorldFile, StartInsideObstacleIsRejected) {
  const World w = worldOf("start: {x_m: 0.5, y_m: 0.5}\nobstacles:\n  - {vertices_m: [0, 0, 1, 0, 1, 1, 0, 1]}\n", "test_world.yaml");
  try {
    checkStartPose(w, 0.35);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("test_world.yaml: start"), std::string::npos) << e.what();
  }
  const World near_wall = worldOf("start: {x_m: 0.2}\nwalls:\n  - {from_m: [0.5, -1], to_m: [0.5, 1]}\n", "test_world.yaml");
  EXPECT_THROW(checkStartPose(near_wall, 0.35), ConfigError);
  EXPECT_NO_THROW(checkStartPose(near_wall, 0.25));
}

// --- ray casting, table-driven ---

struct RayCase {
  const char* name;
  const char* world_yaml;
  Vec2 origin;
  double yaw_rad;
  std::optional<double> expect_m;
};

inline void PrintTo(const RayCase& c, std::ostream* os) { *os << c.name; }

class RayCast : public ::testing::TestWithParam<RayCase> {};

TEST_P(RayCast, FirstHitDistance) {
  const auto& c = GetParam();
  const World w = worldOf(c.world_yaml, "test_world.yaml");
  const auto hit = castRay(w, c.origin, c.yaw_rad, 10.0);
  if (!c.expect_m) {
    EXPECT_FALSE(hit) << c.name << " hit at " << *hit;
  } else {
    ASSERT_TRUE(hit) << c.name;
    EXPECT_NEAR(*hit, *c.expect_m, 1e-9) << c.name;
  }
}

// U-shaped (concave) obstacle opening to -x: outer 0..3 x 0..3, notch 0..2 x 1..2.
constexpr const char* kUShape = "obstacles:\n  - {vertices_m: [0,0, 3,0, 3,3, 0,3, 0,2, 2,2, 2,1, 0,1]}\n";
constexpr double kPi = std::numbers::pi;

INSTANTIATE_TEST_SUITE_P(
    Table, RayCast,
    ::testing::Values(
        RayCase{"segment ahead", "walls:\n  - {from_m: [2, -1], to_m: [2, 1]}\n", {0, 0}, 0.0, 2.0},
        RayCase{"segment behind", "walls:\n  - {from_m: [2, -1], to_m: [2, 1]}\n", {0, 0}, kPi, std::nullopt},
        RayCase{"segment at 45 deg", "walls:\n  - {from_m: [1, -5], to_m: [1, 5]}\n", {0, 0}, kPi / 4, std::sqrt(2.0)},
        RayCase{"segment passed by", "walls:\n  - {from_m: [2, 0.5], to_m: [2, 1]}\n", {0, 0}, 0.0, std::nullopt},
        RayCase{"segment endpoint", "walls:\n  - {from_m: [2, 0], to_m: [2, 1]}\n", {0, 0}, 0.0, 2.0},
        RayCase{"parallel segment", "walls:\n  - {from_m: [1, 0.5], to_m: [3, 0.5]}\n", {0, 0}, 0.0, std::nullopt},
        RayCase{"beyond max range", "walls:\n  - {from_m: [20, -1], to_m: [20, 1]}\n", {0, 0}, 0.0, std::nullopt},
        RayCase{"nearest of two", "walls:\n  - {from_m: [3, -1], to_m: [3, 1]}\n  - {from_m: [1.5, -1], to_m: [1.5, 1]}\n",
                {0, 0}, 0.0, 1.5},
        RayCase{"polygon front face", "obstacles:\n  - {vertices_m: [1,-1, 2,-1, 2,1, 1,1]}\n", {0, 0}, 0.0, 1.0},
        RayCase{"polygon from above", "obstacles:\n  - {vertices_m: [1,-1, 2,-1, 2,1, 1,1]}\n", {1.5, 4}, -kPi / 2,
                3.0},
        RayCase{"polygon missed", "obstacles:\n  - {vertices_m: [1,-1, 2,-1, 2,1, 1,1]}\n", {0, 0}, kPi / 2,
                std::nullopt},
        RayCase{"concave: into the notch", kUShape, {-1, 1.5}, 0.0, 3.0},
        RayCase{"concave: at the arm", kUShape, {-1, 2.5}, 0.0, 1.0},
        RayCase{"concave: over the top", kUShape, {-1, 3.5}, 0.0, std::nullopt},
        RayCase{"polyline wall", "walls:\n  - {points_m: [1,-1, 1,1, 3,1], closed: true}\n", {1.5, 0}, 0.0,
                0.5}),
    [](const auto& info) {
      std::string n = info.param.name;
      for (auto& ch : n)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      return n;
    });

TEST(Clearance, SegmentsAndPolygons) {
  const World w = worldOf(kUShape, "test_world.yaml");
  EXPECT_DOUBLE_EQ(clearance(w, {-1, 1.5}), std::sqrt(1.25));  // to the notch corners (0, 1), (0, 2)
  EXPECT_DOUBLE_EQ(clearance(w, {1.0, 1.5}), 0.5);  // inside the notch: 0.5 to its floor and ceiling
  EXPECT_DOUBLE_EQ(clearance(w, {2.5, 0.5}), 0.0);  // inside the solid part
  EXPECT_DOUBLE_EQ(clearance(w, {4, 4}), std::sqrt(2.0));
}

TEST(FloorLines, WidthIsRespected) {
  const World w = worldOf("floor_lines:\n  - {from_m: [0, 0], to_m: [2, 0], width_m: 0.04}\n", "test_world.yaml");
  EXPECT_TRUE(onFloorLine(w, {1.0, 0.0}));
  EXPECT_TRUE(onFloorLine(w, {1.0, 0.019}));
  EXPECT_FALSE(onFloorLine(w, {1.0, 0.021}));
  EXPECT_FALSE(onFloorLine(w, {2.1, 0.0}));
}
