// Config loading: defaults, ranges, unknown keys, errors naming file and key.
#include <gtest/gtest.h>

#include "shared/config/robot_config.hpp"
#include "tests/support/paths.hpp"

using namespace inspect::config;

namespace {
std::string robotConfigError(const std::string& yaml) {
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
  const auto c = loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  EXPECT_DOUBLE_EQ(c.geometry.l3_m, 0.046);
  EXPECT_NEAR(c.ultrasonic.mounts[2].yaw_rad, 1.5708, 1e-9);
}

TEST(Config, OutOfRangeNamesFileKeyAndRange) {
  const auto e = robotConfigError("geometry:\n  track_m: -1\n");
  EXPECT_NE(e.find("robot.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("geometry.track_m"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

TEST(Config, NotANumber) {
  const auto e = robotConfigError("limits:\n  max_v_m_s: fast\n");
  EXPECT_NE(e.find("limits.max_v_m_s"), std::string::npos) << e;
  EXPECT_NE(e.find("'fast' is not a number"), std::string::npos) << e;
}

TEST(Config, UnknownKeyIsReported) {
  const auto e = robotConfigError("geometry:\n  wheel_radus_m: 0.2\n");
  EXPECT_NE(e.find("geometry.wheel_radus_m: unknown key"), std::string::npos) << e;
}

TEST(Config, SyntaxErrorNamesLine) {
  const auto e = robotConfigError("geometry:\n  track_m: [1,\n");
  EXPECT_NE(e.find("robot.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("syntax"), std::string::npos) << e;
}

TEST(Config, CameraMount) {
  const auto d = loadRobotConfig(ConfigNode::loadString("", "x.yaml"));
  EXPECT_DOUBLE_EQ(d.camera.x_m, 0.20);
  EXPECT_DOUBLE_EQ(d.camera.y_m, 0.0);
  EXPECT_DOUBLE_EQ(d.camera.z_m, 0.60);
  EXPECT_DOUBLE_EQ(d.camera.hfov_deg, 60.0);
  const auto shipped = loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  EXPECT_DOUBLE_EQ(shipped.camera.x_m, d.camera.x_m);
  EXPECT_DOUBLE_EQ(shipped.camera.z_m, d.camera.z_m);
  EXPECT_DOUBLE_EQ(shipped.camera.hfov_deg, d.camera.hfov_deg);
  const auto c = loadRobotConfig(ConfigNode::loadString("camera:\n  z_m: 1.2\n  hfov_deg: 90\n", "x.yaml"));
  EXPECT_DOUBLE_EQ(c.camera.z_m, 1.2);
  EXPECT_DOUBLE_EQ(c.camera.hfov_deg, 90.0);
  EXPECT_NE(robotConfigError("camera:\n  hfov_deg: 180\n").find("camera.hfov_deg"), std::string::npos);
  EXPECT_NE(robotConfigError("camera:\n  hfov_deg: 180\n").find("out of range"), std::string::npos);
  EXPECT_NE(robotConfigError("camera:\n  z_m: 0\n").find("camera.z_m"), std::string::npos);
  EXPECT_NE(robotConfigError("camera:\n  height_m: 1\n").find("camera.height_m: unknown key"), std::string::npos);
}

TEST(Config, WideCameraIsOptionalAndCheckedLikeThePtzHead) {
  EXPECT_FALSE(loadRobotConfig(ConfigNode::loadString("", "x.yaml")).wide_camera);
  const auto shipped = loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  ASSERT_TRUE(shipped.wide_camera);
  EXPECT_DOUBLE_EQ(shipped.wide_camera->hfov_deg, 120.0);
  // Keys left out take the shipped head's values, not the PTZ head's.
  const auto c = loadRobotConfig(ConfigNode::loadString("wide_camera:\n  z_m: 0.4\n", "x.yaml"));
  ASSERT_TRUE(c.wide_camera);
  EXPECT_DOUBLE_EQ(c.wide_camera->z_m, 0.4);
  EXPECT_DOUBLE_EQ(c.wide_camera->hfov_deg, shipped.wide_camera->hfov_deg);
  EXPECT_DOUBLE_EQ(c.wide_camera->x_m, shipped.wide_camera->x_m);
  EXPECT_DOUBLE_EQ(c.camera.hfov_deg, 60.0) << "the PTZ head is untouched";
  const auto e = robotConfigError("wide_camera:\n  hfov_deg: 170\n");
  EXPECT_NE(e.find("wide_camera.hfov_deg"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  EXPECT_NE(robotConfigError("wide_camera:\n  fov: 1\n").find("wide_camera.fov: unknown key"), std::string::npos);
}

TEST(Config, WrongMountCount) {
  const auto e = robotConfigError("ultrasonic:\n  mounts:\n    - {x_m: 0, y_m: 0, yaw_rad: 0}\n");
  EXPECT_NE(e.find("exactly 4"), std::string::npos) << e;
}

TEST(GasConfig, ShippedChannelsAreTheDefaults) {
  const auto c = loadRobotConfigFile(inspect::test::srcPath("config/robot.yaml"));
  const auto d = defaultGasConfig();
  ASSERT_EQ(c.gas.channels.size(), d.channels.size());
  for (std::size_t i = 0; i < d.channels.size(); ++i) {
    const auto &a = c.gas.channels[i], &b = d.channels[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.unit, b.unit);
    EXPECT_EQ(a.sensor, b.sensor);
    EXPECT_DOUBLE_EQ(a.scale, b.scale);
    EXPECT_DOUBLE_EQ(a.range_max, b.range_max);
    EXPECT_DOUBLE_EQ(a.t90_s, b.t90_s);
    EXPECT_DOUBLE_EQ(a.noise, b.noise);
    EXPECT_DOUBLE_EQ(a.background, b.background);
    EXPECT_EQ(a.direction, b.direction);
    EXPECT_DOUBLE_EQ(a.alarm_low, b.alarm_low);
    EXPECT_DOUBLE_EQ(a.alarm_high, b.alarm_high);
    EXPECT_DOUBLE_EQ(a.hysteresis, b.hysteresis);
    EXPECT_DOUBLE_EQ(a.min_duration_s, b.min_duration_s);
    ASSERT_EQ(a.cross.size(), b.cross.size());
    for (std::size_t k = 0; k < a.cross.size(); ++k) {
      EXPECT_EQ(a.cross[k].gas, b.cross[k].gas);
      EXPECT_DOUBLE_EQ(a.cross[k].factor, b.cross[k].factor);
    }
  }
  EXPECT_NEAR(d.channels[0].tau_s(), 6.0 / std::log(10.0), 1e-12);
  EXPECT_TRUE(loadRobotConfig(ConfigNode::loadString("{}", "r.yaml")).gas.channels.empty()) << "absent = none";
}

TEST(GasConfig, BadChannelsNameTheKey) {
  auto err = [](const std::string& channel) {
    try {
      loadRobotConfig(ConfigNode::loadString("gas:\n  channels:\n    - " + channel + "\n", "r.yaml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("{name: CH4, unit: x, range_max: 100, alarm_low: 20, alarm_high: 10}").find("alarm_high"),
            std::string::npos);
  EXPECT_NE(err("{name: O2, unit: x, range_max: 30, direction: falling, alarm_low: 18, alarm_high: 19.5}")
                .find("falling"),
            std::string::npos);
  EXPECT_NE(err("{name: 'C H4', unit: x, range_max: 100, alarm_low: 10, alarm_high: 20}").find("name"),
            std::string::npos);
  EXPECT_NE(err("{name: CH4, unit: x, range_max: 1000, alarm_low: 10, alarm_high: 20}").find("raw counts"),
            std::string::npos);
  EXPECT_NE(err("{name: CH4, unit: x, range_max: 100, alarm_low: 10, alarm_high: 20, t90_s: 0}").find("t90_s"),
            std::string::npos);
  EXPECT_NE(err("{name: CH4, unit: x, range_max: 100, alarm_low: 10, alarm_high: 20, "
                "cross_sensitivity: [{gas: NO2, factor: 1}]}")
                .find("NO2"),
            std::string::npos);
  EXPECT_NE(robotConfigError("gas:\n  channels:\n    - {name: CH4, unit: x, range_max: 100, alarm_low: 10, alarm_high: 20, "
                    "colour: red}\n")
                .find("colour"),
            std::string::npos);
}
