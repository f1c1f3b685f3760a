// mcu_sim command line parsing.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sim/mcu_sim/sim_options.hpp"

using namespace inspect::sim;

namespace {
std::string errorOf(const std::vector<std::string>& args) {
  try {
    (void)parseSimOptions(args);
  } catch (const inspect::cli::UsageError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SimOptions, Defaults) {
  const auto o = parseSimOptions({"--world", "w.yaml"});
  EXPECT_EQ(o.world_path, "w.yaml");
  EXPECT_EQ(o.robot_path, "config/robot.yaml");
  EXPECT_DOUBLE_EQ(o.rate, 1.0);
  EXPECT_FALSE(o.duration_s);
  EXPECT_EQ(o.seed, 1u);
  EXPECT_TRUE(o.pty_link.empty());
  EXPECT_TRUE(o.truth_path.empty());
}

TEST(SimOptions, AllFlags) {
  const auto o = parseSimOptions({"--world", "w.yaml", "--robot", "r.yaml", "--pty-link", "/tmp/mcu", "--truth",
                                  "t.csv", "--rate=5", "--duration", "3", "--seed", "77"});
  EXPECT_EQ(o.robot_path, "r.yaml");
  EXPECT_EQ(o.pty_link, "/tmp/mcu");
  EXPECT_EQ(o.truth_path, "t.csv");
  EXPECT_DOUBLE_EQ(o.rate, 5.0);
  EXPECT_DOUBLE_EQ(*o.duration_s, 3.0);
  EXPECT_EQ(o.seed, 77u);
  EXPECT_EQ(parseSimOptions({"--world", "w", "--seed", "18446744073709551615"}).seed, 18446744073709551615ull);
}

TEST(SimOptions, Camera) {
  const auto none = parseSimOptions({"--world", "w"});
  EXPECT_TRUE(none.camera.path.empty());
  EXPECT_EQ(none.camera.width, 640);
  EXPECT_EQ(none.camera.height, 480);
  EXPECT_DOUBLE_EQ(none.camera.fps, 30.0);
  EXPECT_TRUE(none.wide_camera.path.empty());
  EXPECT_DOUBLE_EQ(none.wide_camera.fps, 15.0);
  const auto o = parseSimOptions({"--world", "w", "--camera", "/dev/shm/cam", "--camera-size=320x240", "--camera-fps", "15",
                                  "--wide-camera", "/dev/shm/wide", "--wide-camera-size", "800x600", "--wide-camera-fps", "5"});
  EXPECT_EQ(o.camera.path, "/dev/shm/cam");
  EXPECT_EQ(o.camera.width, 320);
  EXPECT_EQ(o.camera.height, 240);
  EXPECT_DOUBLE_EQ(o.camera.fps, 15.0);
  EXPECT_EQ(o.wide_camera.path, "/dev/shm/wide");
  EXPECT_EQ(o.wide_camera.width, 800);
  EXPECT_EQ(o.wide_camera.height, 600);
  EXPECT_DOUBLE_EQ(o.wide_camera.fps, 5.0);
}

TEST(SimOptions, HelpNeedsNoWorld) { EXPECT_TRUE(parseSimOptions({"--help"}).help); }

TEST(SimOptions, ErrorsNameTheFlag) {
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{}, "--world: required"},
      {{"--world", "w", "--wide-camera-fps", "5"}, "--wide-camera-fps: needs --wide-camera"},
      {{"--world", "w", "--camera", "/dev/shm/c", "--wide-camera", "/dev/shm/c"}, "--wide-camera: must not be --camera's slot"},
      {{"--world", "w", "--bogus"}, "--bogus: unknown option"},
      {{"--world", "w", "--rate", "0.05"}, "--rate: 0.05 is out of range [0.1, 100]"},
      {{"--world", "w", "--rate", "101"}, "--rate: 101 is out of range"},
      {{"--world", "w", "--rate", "fast"}, "--rate: 'fast' is not a number"},
      {{"--world", "w", "--duration", "0"}, "--duration: 0 is out of range"},
      {{"--world", "w", "--duration", "-1"}, "--duration: -1 is out of range"},
      {{"--world", "w", "--seed", "-3"}, "--seed: '-3' is not a whole number in [0, "},
      {{"--world", "w", "--seed", "1.5"}, "--seed: '1.5'"},
      {{"--world", "w", "--truth"}, "--truth: missing value"},
      {{"--world", "w", "--truth="}, "--truth: empty value"},
      {{"--world", "w", "--people-wait-motion=1"}, "--people-wait-motion: takes no value"},
      {{"--world"}, "--world: missing value"},
      {{"--world", "w", "--camera="}, "--camera: empty value"},
      {{"--world", "w", "--camera-size", "640x480"}, "--camera-size: needs --camera"},
      {{"--world", "w", "--camera-fps", "10"}, "--camera-fps: needs --camera"},
      {{"--world", "w", "--camera", "c", "--camera-size", "640"}, "--camera-size: '640' is not WxH with W and H in [64, 4096]"},
      {{"--world", "w", "--camera", "c", "--camera-size", "32x32"}, "--camera-size: '32x32' is not WxH"},
      {{"--world", "w", "--camera", "c", "--camera-size", "640x480x"}, "--camera-size: '640x480x' is not WxH"},
      {{"--world", "w", "--camera", "c", "--camera-fps", "0"}, "--camera-fps: 0 is out of range [1, 120]"},
      {{"--world", "w", "--hil", "t", "--rate", "2"}, "--rate: the firmware in the loop runs in real time"},
      {{"--world", "w", "--hil", "t", "--pty-link", "p"}, "--pty-link: with --hil the Pi's line is the board's"},
      {{"--world", "w", "--hil", "t", "--freeze-on-stall"}, "--freeze-on-stall: with --hil the board's clock runs on"},
  };
  for (const auto& c : cases) {
    const auto e = errorOf(c.args);
    EXPECT_EQ(e.rfind(c.expect, 0), 0u) << "got: " << e << " want: " << c.expect;
  }
}

TEST(SimOptions, UsageListsEveryFlag) {
  const auto u = simUsage();
  for (const char* f : {"--world", "--robot", "--pty-link", "--truth", "--rate", "--duration", "--seed", "--camera",
                        "--camera-size", "--camera-fps", "--help"})
    EXPECT_NE(u.find(f), std::string::npos) << f;
}
