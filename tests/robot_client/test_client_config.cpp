// robot_client configuration: shipped file, overrides, and errors.
#include <gtest/gtest.h>

#include "robot_client/client_config.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;

namespace {
std::string clientConfigError(const std::string& yaml) {
  try {
    const auto root = config::ConfigNode::loadString(yaml, "client.yaml");
    (void)client::loadClientConfig(root);
    root.checkKnown();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ClientConfig, ShippedFileLoads) {
  const auto c = client::loadClientConfigFile(inspect::test::srcPath("config/client.yaml"));
  EXPECT_EQ(c.server_port, 7600);
  EXPECT_DOUBLE_EQ(c.safety.link_timeout_s, 0.25);  // docs/failsafes.md
  EXPECT_EQ(c.baud, 115200);
}

TEST(ClientConfig, Errors) {
  EXPECT_NE(clientConfigError("robot_id: 'bad id!'").find("robot_id"), std::string::npos);
  EXPECT_NE(clientConfigError("server:\n  port: 70000\n").find("server.port: 70000 is out of range"), std::string::npos);
  EXPECT_NE(clientConfigError("serial:\n  baud: 115201\n").find("not a standard rate"), std::string::npos);
  EXPECT_NE(clientConfigError("safety:\n  link_timeout_s: 0\n").find("safety.link_timeout_s"), std::string::npos);
  EXPECT_NE(clientConfigError("server:\n  prot: 1\n").find("server.prot: unknown key"), std::string::npos);
  EXPECT_NE(clientConfigError("server:\n  port: 7600.5\n").find("not a whole number"), std::string::npos);
  EXPECT_NE(clientConfigError("events:\n  max_pending: 3\n").find("events.max_pending: 3 is out of range"),
            std::string::npos);
}

TEST(ClientConfig, RobotIds) {
  EXPECT_TRUE(client::validRobotId("robot_1-A"));
  EXPECT_FALSE(client::validRobotId(""));
  EXPECT_FALSE(client::validRobotId(std::string(65, 'a')));
  EXPECT_FALSE(client::validRobotId("a b"));
}

TEST(ClientConfig, Video) {
  const auto c = client::loadClientConfigFile(inspect::test::srcPath("config/client.yaml"));
  const client::VideoParams d;
  EXPECT_EQ(c.video.enabled, d.enabled);
  EXPECT_EQ(c.video.source, "synthetic");
  EXPECT_EQ(c.video.width, 640);
  EXPECT_EQ(c.video.port, 5600);
  EXPECT_EQ(c.video.mtu, 1200);
  EXPECT_EQ(c.video.encoder, "libx264");
  EXPECT_NE(clientConfigError("video:\n  width: 641\n").find("video.width: width and height must be even"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  fps: 0\n").find("video.fps: 0 is out of range"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  encoder: h265\n").find("video.encoder: 'h265' is not one of"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  preset: slow\n").find("video.preset: 'slow'"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  bitrate_kbps: 10\n").find("video.bitrate_kbps: 10 is out of range"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  mtu: 100\n").find("video.mtu: 100 is out of range"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  pixel_format: MJPEG\n").find("video.pixel_format: a FOURCC is 4 characters"),
            std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  source: ''\n").find("video.source: must not be empty"), std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  gopp: 3\n").find("video.gopp: unknown key"), std::string::npos);
  EXPECT_TRUE(c.video.adapt);
  EXPECT_EQ(c.video.adapt_min_kbps, 500);
  EXPECT_EQ(c.video.adapt_max_kbps, 0);
  EXPECT_NE(clientConfigError("video:\n  adapt:\n    min_kbps: 10\n").find("video.adapt.min_kbps: 10 is out of range"),
            std::string::npos);
  EXPECT_NE(clientConfigError("video:\n  adapt:\n    min_kbps: 500\n    max_kbps: 400\n")
                .find("video.adapt.max_kbps: 400 is below min_kbps 500"),
            std::string::npos);
}

TEST(ClientConfig, Perception) {
  const auto c = client::loadClientConfigFile(inspect::test::srcPath("config/client.yaml"));
  EXPECT_TRUE(c.perception.enabled);
  EXPECT_EQ(c.perception.detector, "hog");
  EXPECT_EQ(c.perception.width, 640);
  EXPECT_DOUBLE_EQ(c.perception.rate_hz, 5.0);
  EXPECT_DOUBLE_EQ(c.perception.max_core_share, 0.5);
  EXPECT_TRUE(c.perception.look_ahead);
  EXPECT_NE(clientConfigError("perception:\n  detector: yolo\n").find("perception.detector: 'yolo' is not one of"),
            std::string::npos);
  EXPECT_NE(clientConfigError("perception:\n  rate_hz: 0\n").find("perception.rate_hz: 0 is out of range"),
            std::string::npos);
  EXPECT_NE(clientConfigError("perception:\n  max_core_share: 2\n").find("perception.max_core_share: 2 is out of range"),
            std::string::npos);
  EXPECT_NE(clientConfigError("perception:\n  lookahead: true\n").find("perception.lookahead: unknown key"),
            std::string::npos);
}

TEST(ClientConfig, WideHead) {
  const auto c = client::loadClientConfigFile(inspect::test::srcPath("config/client.yaml"));
  EXPECT_EQ(c.wide_head.source, "") << "no wide head unless configured";
  EXPECT_EQ(c.wide_head.width, 480);
  EXPECT_EQ(c.wide_head.height, 360);
  EXPECT_EQ(c.wide_head.group_threshold, 1);
  EXPECT_EQ(c.wide_head.detector, "hog");
  EXPECT_DOUBLE_EQ(c.wide_head.fps, 15.0);
  // Without the section: the same defaults.
  const auto d = client::loadClientConfig(config::ConfigNode::loadString("robot_id: r\n", "client.yaml"));
  EXPECT_EQ(d.wide_head.width, 480);
  EXPECT_EQ(d.wide_head.group_threshold, 1);
  const auto e = client::loadClientConfig(
      config::ConfigNode::loadString("wide_head:\n  source: sim:/dev/shm/w\n  rate_hz: 4\n", "client.yaml"));
  EXPECT_EQ(e.wide_head.source, "sim:/dev/shm/w");
  EXPECT_DOUBLE_EQ(e.wide_head.rate_hz, 4.0);
  EXPECT_NE(clientConfigError("wide_head:\n  source: synthetic\n").find("wide_head.source: the synthetic picture shows nobody"),
            std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  width: 481\n").find("wide_head.width: width and height must be even"),
            std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  detector: yolo\n").find("wide_head.detector: 'yolo' is not one of"),
            std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  fps: 0\n").find("wide_head.fps: 0 is out of range"), std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  pixel_format: MJPEG\n").find("wide_head.pixel_format: a FOURCC"),
            std::string::npos);
  EXPECT_TRUE(c.wide_head.floor_band) << "the floor band on both heads (bench_people)";
  EXPECT_TRUE(c.perception.floor_band);
  EXPECT_FALSE(client::loadClientConfig(config::ConfigNode::loadString("perception:\n  floor_band: false\n", "client.yaml"))
                   .perception.floor_band);
  // Streamed only when asked (docs/video.md "The wide head's stream").
  EXPECT_FALSE(c.wide_head.stream);
  EXPECT_EQ(c.wide_head.bitrate_kbps, 800);
  const auto f = client::loadClientConfig(
      config::ConfigNode::loadString("wide_head:\n  stream: true\n  bitrate_kbps: 600\n", "client.yaml"));
  EXPECT_TRUE(f.wide_head.stream);
  EXPECT_EQ(f.wide_head.bitrate_kbps, 600);
  EXPECT_NE(clientConfigError("wide_head:\n  stream: maybe\n").find("wide_head.stream"), std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  bitrate_kbps: 10\n").find("wide_head.bitrate_kbps: 10 is out of range"),
            std::string::npos);
  EXPECT_NE(clientConfigError("wide_head:\n  streamed: true\n").find("wide_head.streamed: unknown key"),
            std::string::npos);
}
