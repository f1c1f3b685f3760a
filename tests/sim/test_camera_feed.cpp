// mcu_sim's camera (sim/mcu_sim/camera_feed.hpp): the truth it takes from
// the simulation (pose, the PTZ set-point from the serial line, the people),
// the pictures it writes into its frame slot, and the real program with
// --camera. Every wait is bounded; no timing is judged.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/config/robot_config.hpp"
#include "shared/serial/frame_codec.hpp"
#include "shared/video/frame_slot.hpp"
#include "shared/video/timecode.hpp"
#include "sim/mcu_sim/camera_feed.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/world_text.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/process.hpp"

using namespace inspect;
using namespace inspect::sim;
using namespace std::chrono_literals;

namespace {

const char* kWorld =
    "start: {x_m: 1.0, y_m: 2.0, theta_rad: 0.5}\n"
    "walls:\n  - {points_m: [-3, -3,  8, -3,  8, 8,  -3, 8], closed: true}\n"
    "pedestrians:\n  - {id: p, route_m: [4.0, 3.0,  5.0, 3.0]}\n";

std::vector<uint8_t> bytesOf(const serial::Message& m) {
  serial::FrameEncoder enc;
  const auto f = enc.encode(m);
  return {f.bytes.begin(), f.bytes.begin() + static_cast<std::ptrdiff_t>(f.size)};
}

}  // namespace

TEST(CameraFeed, TakesThePoseThePtzSetPointAndThePeopleFromTheSimulation) {
  const config::RobotConfig robot;
  Simulation sim(robot, test::worldOf(kWorld), 1);
  test::TempDir dir("camera_feed");
  CameraFeed feed(sim.world(), robot.camera, {dir / "cam.slot", 160, 120, 30});
  sim.receive(bytesOf(serial::PtzCommand{5236, -1745, 0}));  // 0.5236 rad left, 0.1745 rad down
  sim.advanceTo(20);
  feed.publish(sim);
  CameraScene s = feed.snapshot();
  EXPECT_NEAR(s.robot.x_m, sim.state().pose.x_m, 1e-12);
  EXPECT_NEAR(s.robot.theta_rad, sim.state().pose.theta_rad, 1e-12);
  EXPECT_NEAR(s.pan_rad, 0.5236, 1e-9);
  EXPECT_NEAR(s.tilt_rad, -0.1745, 1e-9);
  EXPECT_NEAR(s.sim_time_s, 0.02, 1e-12);
  ASSERT_EQ(s.people.size(), 1u);
  EXPECT_NEAR(s.people[0].position.x, sim.pedestrians().agent(0).position_m.x(), 1e-12);
  EXPECT_NEAR(s.people[0].radius_m, 0.25, 1e-12);
  // Home brings the camera back to straight ahead.
  sim.receive(bytesOf(serial::PtzCommand{5236, -1745, 1}));
  sim.advanceTo(30);
  feed.publish(sim);
  s = feed.snapshot();
  EXPECT_EQ(s.pan_rad, 0.0);
  EXPECT_EQ(s.tilt_rad, 0.0);
}

TEST(CameraFeed, AFixedHeadLooksAheadWhereverThePtzPoints) {
  const config::RobotConfig robot = config::loadRobotConfigFile(test::srcPath("config/robot.yaml"));
  ASSERT_TRUE(robot.wide_camera);
  Simulation sim(robot, test::worldOf(kWorld), 1);
  test::TempDir dir("camera_feed");
  CameraFeedOptions opt{dir / "wide.slot", 160, 120, 30};
  opt.follows_ptz = false;
  CameraFeed feed(sim.world(), *robot.wide_camera, opt);
  sim.receive(bytesOf(serial::PtzCommand{5236, -1745, 0}));
  sim.advanceTo(20);
  feed.publish(sim);
  const CameraScene s = feed.snapshot();
  EXPECT_EQ(s.pan_rad, 0.0);
  EXPECT_EQ(s.tilt_rad, 0.0);
  EXPECT_NEAR(s.robot.theta_rad, sim.state().pose.theta_rad, 1e-12);
  EXPECT_EQ(s.people.size(), 1u);
}

TEST(CameraFeed, WritesPicturesWithTheirTimeCodeAndRemovesTheSlotWhenDestroyed) {
  const config::RobotConfig robot;
  Simulation sim(robot, test::worldOf(kWorld), 1);
  test::TempDir dir("camera_feed");
  const std::string path = dir / "cam.slot";
  auto feed = std::make_unique<CameraFeed>(sim.world(), robot.camera, CameraFeedOptions{path, 320, 240, 50});
  ASSERT_TRUE(test::exists(path)) << "the slot exists before the first picture";
  feed->publish(sim);
  feed->start();
  video::FrameSlotReader reader(path);
  EXPECT_EQ(reader.width(), 320);
  EXPECT_EQ(reader.height(), 240);
  EXPECT_NEAR(reader.fps(), 50, 1e-9);
  cv::Mat pic(240, 320, CV_8UC3);
  uint64_t seq = 0;
  for (int k = 0; k < 3; ++k) {
    const auto f = reader.readNewer(seq, pic.data, pic.step, 3000ms);
    ASSERT_TRUE(f) << "picture " << k;
    EXPECT_GT(f->seq, seq);
    seq = f->seq;
    const auto code = video::readTimecode(pic);
    ASSERT_TRUE(code) << "picture " << k;
    EXPECT_EQ(code->frame_index, f->frame_index);
    EXPECT_EQ(code->capture_us, f->capture_us & ((uint64_t{1} << 48) - 1));
  }
  feed->stop();
  EXPECT_GE(feed->stats().frames, 3u);
  EXPECT_NE(feed->summary().find("camera " + path + " 320x240 at 50 fps: frames="), std::string::npos)
      << feed->summary();
  feed.reset();
  EXPECT_FALSE(test::exists(path));
  EXPECT_TRUE(reader.closed());
  const auto t0 = std::chrono::steady_clock::now();
  // Pictures written after the last one read stay readable; past the newest,
  // a closed slot answers at once.
  EXPECT_FALSE(reader.readNewer(reader.latestSeq(), pic.data, pic.step, 2000ms));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1000ms) << "a closed slot is not waited for";
}

TEST(CameraFeed, McuSimRendersItsCameraIntoTheSlotOfCamera) {
  test::TempDir dir("mcu_sim_camera");
  const std::string path = dir / "cam.slot", wide = dir / "wide.slot";
  test::Process sim = test::Process::spawn(
      {test::binPath("mcu_sim"), "--world", test::srcPath("config/worlds/gas_lab.yaml"), "--robot",
       test::srcPath("config/robot.yaml"), "--camera", path, "--camera-size", "320x240", "--camera-fps", "20",
       "--wide-camera", wide, "--wide-camera-size", "320x180", "--duration", "3"},
      dir / "out.txt", dir / "err.txt");
  ASSERT_TRUE(test::waitUntil([&] { return test::exists(path); }, 10.0)) << test::readFile(dir / "err.txt");
  video::FrameSlotReader reader(path);
  EXPECT_EQ(reader.writerPid(), sim.pid());
  EXPECT_EQ(reader.width(), 320);
  cv::Mat pic(240, 320, CV_8UC3);
  const auto f = reader.readNewer(0, pic.data, pic.step, 3000ms);
  ASSERT_TRUE(f);
  EXPECT_TRUE(video::readTimecode(pic));
  // Not a flat picture: walls, floor and ceiling differ.
  cv::Scalar mean, dev;
  cv::meanStdDev(pic, mean, dev);
  EXPECT_GT(dev[1], 10.0);
  // The wide head's slot beside it, at its own size.
  ASSERT_TRUE(test::waitUntil([&] { return test::exists(wide); }, 10.0)) << test::readFile(dir / "err.txt");
  video::FrameSlotReader wide_reader(wide);
  EXPECT_EQ(wide_reader.width(), 320);
  EXPECT_EQ(wide_reader.height(), 180);
  cv::Mat wide_pic(180, 320, CV_8UC3);
  ASSERT_TRUE(wide_reader.readNewer(0, wide_pic.data, wide_pic.step, 3000ms));
  EXPECT_TRUE(video::readTimecode(wide_pic));
  const auto rc = sim.wait(20.0);
  ASSERT_TRUE(rc.has_value());
  EXPECT_EQ(*rc, 0) << test::readFile(dir / "err.txt");
  const std::string out = test::readFile(dir / "out.txt");
  EXPECT_NE(out.find("mcu_sim: camera " + path + " (320x240 at 20 fps; robot_client --video-source sim:" + path),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("mcu_sim: camera " + path + " 320x240 at 20 fps: frames="), std::string::npos) << out;
  EXPECT_NE(out.find("mcu_sim: wide camera " + wide + " (320x180 at 15 fps; a sim:" + wide + " video source)"),
            std::string::npos)
      << out;
  EXPECT_FALSE(test::exists(path)) << "removed at the end";
  EXPECT_FALSE(test::exists(wide)) << "removed at the end";
}

TEST(CameraFeed, McuSimRefusesASlotPathItCannotUse) {
  test::TempDir dir("mcu_sim_camera");
  test::writeFile(dir / "notes.txt", "not a frame slot\n");
  for (const auto& [path, why] : {std::pair{dir / "notes.txt", "exists and is not a frame slot"},
                                  std::pair{dir / "no/such/dir/cam", "cannot create"}}) {
    test::Process sim = test::Process::spawn({test::binPath("mcu_sim"), "--world",
                                              test::srcPath("config/worlds/empty.yaml"), "--robot",
                                              test::srcPath("config/robot.yaml"), "--camera", path, "--duration", "1"},
                                             dir / "out.txt", dir / "err.txt");
    const auto rc = sim.wait(10.0);
    ASSERT_TRUE(rc.has_value());
    EXPECT_EQ(*rc, 1);
    const std::string err = test::readFile(dir / "err.txt");
    EXPECT_NE(err.find("mcu_sim: " + path + ": " + why), std::string::npos) << err;
  }
  EXPECT_EQ(test::readFile(dir / "notes.txt"), "not a frame slot\n") << "left alone";
}
