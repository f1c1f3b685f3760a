// Config loading: defaults, ranges, unknown keys, errors naming file and key.
#include <gtest/gtest.h>

#include "shared/config/robot_config.hpp"

using namespace inspect::config;

namespace {
std::string errorOf(const std::string& yaml) {
  try {
    const auto root = ConfigNode::loadString(yaml, "robot.yaml");
    (void)loadRobotConfig(root);
    root.checkKnown();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Config, EmptyFileGivesPaperDefaults) {
  const auto c = loadRobotConfig(ConfigNode::loadString("", "x.yaml"));
  EXPECT_DOUBLE_EQ(c.geometry.wheel_radius_m, 0.2);
  EXPECT_DOUBLE_EQ(c.geometry.track_m, 0.438);
}

TEST(Config, ShippedRobotYamlLoads) {
  const auto c = loadRobotConfigFile(std::string(INSPECT_SOURCE_DIR) + "/config/robot.yaml");
  EXPECT_DOUBLE_EQ(c.geometry.l3_m, 0.046);
  EXPECT_NEAR(c.ultrasonic.mounts[2].yaw_rad, 1.5708, 1e-9);
}

TEST(Config, OutOfRangeNamesFileKeyAndRange) {
  const auto e = errorOf("geometry:\n  track_m: -1\n");
  EXPECT_NE(e.find("robot.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("geometry.track_m"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

TEST(Config, NotANumber) {
  const auto e = errorOf("limits:\n  max_v_m_s: fast\n");
  EXPECT_NE(e.find("limits.max_v_m_s"), std::string::npos) << e;
  EXPECT_NE(e.find("'fast' is not a number"), std::string::npos) << e;
}

TEST(Config, UnknownKeyIsReported) {
  const auto e = errorOf("geometry:\n  wheel_radus_m: 0.2\n");
  EXPECT_NE(e.find("geometry.wheel_radus_m: unknown key"), std::string::npos) << e;
}

TEST(Config, SyntaxErrorNamesLine) {
  const auto e = errorOf("geometry:\n  track_m: [1,\n");
  EXPECT_NE(e.find("robot.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("syntax"), std::string::npos) << e;
}

TEST(Config, WrongMountCount) {
  const auto e = errorOf("ultrasonic:\n  mounts:\n    - {x_m: 0, y_m: 0, yaw_rad: 0}\n");
  EXPECT_NE(e.find("exactly 4"), std::string::npos) << e;
}
