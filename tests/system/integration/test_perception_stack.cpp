// People seen by the camera through the real programs (docs/human-awareness.md,
// "Detection on the robot"): mcu_sim renders its camera with a person standing
// ahead, robot_client reads it as its video source (sim:PATH), detects on a
// thread of its own and sends the person's bearing and foot-row range in
// telemetry; the server's console shows them, and the robot's people
// tracker has the person beyond its sonars' reach. Pointing the camera away
// makes perception say so (sonar only ahead).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <regex>
#include <string>

#include "tests/support/paths.hpp"
#include "tests/support/stack.hpp"

using namespace inspect::test;

namespace {
/// How runWithCamera runs the robot's heads.
struct Heads {
  bool wide = false;         // mcu_sim --wide-camera, robot_client --wide-video-source
  bool wide_stream = false;  // ...and --wide-stream, with the Foxglove bridge on
  /// Called once the robot's programs are started, while the script runs.
  std::function<void(Stack&)> during;
  std::vector<std::string> client_args;  // more robot_client arguments
};

/// Runs the server's `script` with one robot in `world` whose video source
/// is mcu_sim's camera (its frame slot /dev/shm/inspect-NAME-PID); the
/// server's output, or "" (a failure added) when it did not end. The robot's
/// programs are stopped.
std::string runWithCamera(Stack& s, const std::string& name, const std::string& world, const std::string& script,
                          const Heads& heads = {}) {
  s.enableVideo();
  if (heads.wide_stream) s.enableFoxglove();
  writeFile(s.dir() / "world.yaml", world);
  writeFile(s.dir() / "server.yaml", "video:\n  window: off\n  forward_base_port: 0\n");
  if (!s.startServer(script, {"--config", s.dir() / "server.yaml", "--runs-dir", s.dir() / "runs"})) {
    ADD_FAILURE() << s.logs();
    return "";
  }
  const std::string slot = "/dev/shm/inspect-" + name + "-" + std::to_string(::getpid());
  std::vector<std::string> sim_args{"--camera", slot}, client_args{"--video-source", "sim:" + slot};
  const std::string wide_slot = slot + "-wide";
  if (heads.wide) {
    sim_args.insert(sim_args.end(), {"--wide-camera", wide_slot});
    client_args.insert(client_args.end(), {"--wide-video-source", "sim:" + wide_slot});
  }
  if (heads.wide_stream) client_args.push_back("--wide-stream");
  client_args.insert(client_args.end(), heads.client_args.begin(), heads.client_args.end());
  auto& robot = s.startRobot("robot1", s.dir() / "world.yaml", {}, sim_args, client_args);
  if (heads.during) heads.during(s);
  const auto rc = s.server().wait(60.0);
  robot.client.terminate();
  robot.sim.terminate();
  const std::string out = s.serverOutput();
  if (!rc) ADD_FAILURE() << "the server's script did not end\n" << s.logs();
  else EXPECT_EQ(*rc, 0) << out;
  EXPECT_EQ(access(slot.c_str(), F_OK), -1) << "mcu_sim removes its frame slot";
  EXPECT_EQ(access(wide_slot.c_str(), F_OK), -1) << "mcu_sim removes its frame slots";
  return rc ? out : "";
}

/// The run.mcap under the stack's runs directory ("" = none).
std::string recordedMcap(Stack& s) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(s.dir() / "runs", ec))
    if (e.is_directory() && std::filesystem::exists(e.path() / "run.mcap")) return (e.path() / "run.mcap").string();
  return "";
}

/// The `robot people:` lines of `video stats` (`robot wide head:` with `head` "wide head").
std::vector<std::string> peopleLines(const std::string& out, const std::string& head = "people") {
  std::vector<std::string> lines;
  const std::string key = "  robot " + head + ": ";
  for (std::size_t at = out.find(key); at != std::string::npos; at = out.find(key, at + 1))
    lines.push_back(out.substr(at, out.find('\n', at) - at));
  return lines;
}
}  // namespace

TEST(PerceptionStack, TheRobotSeesAPersonAheadWithItsCameraAndSaysWhenItLooksAway) {
  Stack s("perception");
  // A person standing 5 m ahead of the lens and 0.5 m to the left (the robot
  // at the origin facing +x, the lens 0.2 m ahead of the axle).
  const std::string out = runWithCamera(s, "perception",
                                        "name: one_person\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\n"
                                        "walls:\n  - {points_m: [-2, -3,  12, -3,  12, 3,  -2, 3], closed: true}\n"
                                        "pedestrians:\n  - {id: p, route_m: [5.2, 0.5]}\n",
                                        "expect robots >= 1 within 15\n"
                                        "record start people ahead\n"
                                        "wait 5\n"
                                        "video stats\n"
                                        "status\n"
                                        "record stop\n"
                                        "ptz 60 0\n"
                                        "wait 2\n"
                                        "video stats\n");
  const auto lines = peopleLines(out);
  ASSERT_EQ(lines.size(), 2u) << out;
  // 1. Looking ahead: the person, at the bearing and range of the truth.
  const double bearing = std::atan2(0.5, 5.0) * 180 / M_PI, range = std::hypot(5.0, 0.5);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(lines[0], m, std::regex(R"(camera\+sonar, 1 seen: ([-+0-9.]+) deg ([0-9.]+) m)")))
      << lines[0] << "\n" << s.logs();
  EXPECT_NEAR(std::stod(m[1]), bearing, 1.0) << lines[0];
  EXPECT_NEAR(std::stod(m[2]), range, 0.3 * range) << lines[0];
  ASSERT_TRUE(std::regex_search(lines[0], m, std::regex(R"(([0-9.]+) Hz, ([0-9.]+) ms, ([0-9]+) pictures)"))) << lines[0];
  EXPECT_GE(std::stod(m[1]), 2.0) << "detections per second: " << lines[0];
  EXPECT_GE(std::stoi(m[3]), 10) << lines[0];
  // The people tracker took the sightings in: 5 m is beyond the sonars'
  // 4.5 m, so the person the robot slows for is the camera's alone.
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(\| person ([0-9.]+) m)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), range + 0.2, 0.3 * range) << "from the axle; the foot-row range is long";
  const std::string tracked = m[0];
  // 2. The camera turned 60 degrees away: the robot says so; the person is out of the picture.
  EXPECT_NE(lines[1].find("camera elsewhere, sonar, 0 seen"), std::string::npos) << lines[1];
  std::printf("%s\n%s\nstatus: %s\n", lines[0].c_str(), lines[1].c_str(), tracked.c_str());

  // 3. The run recorded while looking ahead: the boxes are on the pictures they were found in, as
  // Foxglove's Image panel pairs them (read by @mcap/core; docs/recording.md).
  const char* reader = std::getenv("INSPECT_MCAP_READER");
  ASSERT_NE(reader, nullptr) << "INSPECT_MCAP_READER: the @mcap/core reader (ctest fixture mcap_reader)";
  const std::string mcap = recordedMcap(s);
  ASSERT_FALSE(mcap.empty()) << out;
  const std::string json = captureOutput(std::string("node ") + reader + " --decode --annotations /robot1/camera_people /robot1/camera " + mcap);
  ASSERT_TRUE(std::regex_search(json, m, std::regex(R"("messages":([0-9]+),"boxes":([0-9]+),"on_a_picture":([0-9]+))")))
      << json;
  const int messages = std::stoi(m[1]), boxes = std::stoi(m[2]), on_a_picture = std::stoi(m[3]);
  EXPECT_GE(messages, 8) << "about 4 detected pictures a second for 5 s: " << json;
  EXPECT_GE(boxes, messages * 8 / 10) << json;
  EXPECT_GE(on_a_picture, messages - 1) << "one may be of a picture from before the run began: " << json;
  EXPECT_NE(json.find("\"person +6 deg "), std::string::npos) << json;
  std::printf("recorded: %s\n", json.c_str());
}

TEST(PerceptionStack, WithAPersonNearWhileMovingTheCameraLooksAheadAndIsGivenBackAfter) {
  // docs/human-awareness.md, "Looking ahead": the operator has pointed the
  // camera 60 degrees left; the robot drives toward a person walking to and
  // fro across its way 3.5 m ahead (the sonars find them); the camera turns
  // ahead while the person is within 4 m and the robot moves, and goes back
  // to 60 degrees 3 s after the robot stopped.
  Stack s("lookahead");
  const std::string out =
      runWithCamera(s, "lookahead",
                    "name: crossing_ahead\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\n"
                    "walls:\n  - {points_m: [-2, -4,  12, -4,  12, 4,  -2, 4], closed: true}\n"
                    "pedestrians:\n  - {id: p, speed_m_s: 0.6, route_m: [3.5, -1.5, 3.5, 1.5], loop: true}\n",
                    "expect robots >= 1 within 15\n"
                    "ptz 60 0\n"
                    "wait 1\n"
                    "drive 0.15 0\n"
                    "wait 3\n"
                    "video stats\n"
                    "stop\n"
                    "wait 5\n"
                    "video stats\n");
  const auto lines = peopleLines(out);
  ASSERT_EQ(lines.size(), 2u) << out;
  EXPECT_NE(lines[0].find("looking ahead for people"), std::string::npos) << lines[0] << "\n" << s.logs();
  EXPECT_EQ(lines[0].find("camera elsewhere"), std::string::npos) << lines[0];
  EXPECT_EQ(lines[1].find("looking ahead for people"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("camera elsewhere"), std::string::npos) << "back at 60 degrees: " << lines[1];
  const std::string client_log = readFile(s.dir() / "robot1-client.err");
  EXPECT_NE(client_log.find("while moving: the camera looks ahead"), std::string::npos) << client_log;
  EXPECT_NE(client_log.find("nobody near: the camera goes back to pan 1.047"), std::string::npos) << client_log;
  std::printf("%s\n%s\n", lines[0].c_str(), lines[1].c_str());
}

TEST(PerceptionStack, TheWideHeadSeesAPersonBesideTheRobotWhomThePtzHeadCannot) {
  // docs/human-awareness.md, "The wide head": a person standing 1.2 m ahead
  // of the wide lens and 1.2 m to its left (45 degrees, 1.7 m): outside the
  // PTZ head's +-30 degrees, and nearer than the PTZ head can see anyone
  // (2.7 m). The wide head (robot.yaml wide_camera, 120 degrees; mcu_sim
  // --wide-camera, robot_client --wide-video-source) finds them, the PTZ head
  // does not, and the robot's tracker has them. The wide head is streamed
  // too (--wide-stream; docs/video.md "The wide head's stream"): the operator
  // sees its pictures and boxes in Foxglove, live and recorded.
  const char* reader = std::getenv("INSPECT_MCAP_READER");
  ASSERT_NE(reader, nullptr) << "INSPECT_MCAP_READER: the @mcap/core reader (ctest fixture mcap_reader)";
  // The npm fixture's folder: @mcap/core's, and the Foxglove client library's.
  const std::string modules = std::filesystem::path(reader).parent_path().string();
  Stack s("widehead");
  Heads heads{.wide = true, .wide_stream = true, .during = [&](Stack& st) {
                // A Foxglove client on the wide head's topics while the script runs.
                const std::string url = "ws://127.0.0.1:" + std::to_string(st.foxglovePort()) + "/";
                auto node = Process::spawn({"/usr/bin/env", "node", srcPath("tests/tools/foxglove_camera_check.js"),
                                            "--modules", modules, "--url", url, "--token", st.foxgloveToken(),
                                            "--video", "/robot1/camera_wide", "--annotations",
                                            "/robot1/camera_wide_people", "--seconds", "8", "--json",
                                            st.dir() / "live.json"},
                                           st.dir() / "node.out", st.dir() / "node.err");
                if (!node.wait(40.0)) ADD_FAILURE() << "the Foxglove client did not finish within 40 s";
              }};
  const std::string out = runWithCamera(s, "widehead",
                                        "name: one_person_beside\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\n"
                                        "walls:\n  - {points_m: [-3, -4,  10, -4,  10, 4,  -3, 4], closed: true}\n"
                                        "pedestrians:\n  - {id: p, route_m: [1.44, 1.2]}\n",
                                        "expect robots >= 1 within 15\n"
                                        "record start wide head\n"
                                        "wait 5\n"
                                        "video wide keyframe\n"
                                        "snapshot wide\n"
                                        "video stats\n"
                                        "status\n"
                                        "record stop\n",
                                        heads);
  const auto ptz = peopleLines(out), wide = peopleLines(out, "wide head");
  ASSERT_EQ(ptz.size(), 1u) << out;
  ASSERT_EQ(wide.size(), 1u) << out << "\n" << s.logs();
  EXPECT_NE(ptz[0].find(", 0 seen"), std::string::npos) << ptz[0];
  // The wide lens is 0.24 m ahead of the axle (config/robot.yaml).
  const double bearing = std::atan2(1.2, 1.2) * 180 / M_PI, range = std::hypot(1.2, 1.2);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(wide[0], m, std::regex(R"(camera\+sonar, 1 seen: ([-+0-9.]+) deg ([0-9.]+) m)")))
      << wide[0] << "\n" << s.logs();
  EXPECT_NEAR(std::stod(m[1]), bearing, 3.0) << wide[0];
  // The foot-row range is coarse this near and this far off the axis: HOG's
  // box ends ~20 px above the soles here (measured 2.7 m for 1.7 m, +59 %;
  // the bench's p90 over the whole head is +39 %). The fusion weighs it so.
  EXPECT_GT(std::stod(m[2]), 0.8 * range) << wide[0];
  EXPECT_LT(std::stod(m[2]), 1.7 * range) << wide[0];
  ASSERT_TRUE(std::regex_search(wide[0], m, std::regex(R"(on 480x360, ([0-9.]+) Hz, ([0-9.]+) ms, ([0-9]+) pictures)")))
      << wide[0];
  EXPECT_GE(std::stod(m[1]), 2.0) << "detections per second: " << wide[0];
  EXPECT_NE(out.find("| wide head 1 seen"), std::string::npos) << "the status line: " << out;
  // The tracker has the person from the wide head alone (45 degrees off is
  // between the sonars' cones: they see the walls), at its coarse range.
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(\| person ([0-9.]+) m)"))) << out;
  EXPECT_GT(std::stod(m[1]), 0.8 * std::hypot(1.44, 1.2)) << out;
  EXPECT_LT(std::stod(m[1]), 1.7 * std::hypot(1.44, 1.2)) << out;
  std::printf("%s\n%s\nstatus: %s\n", ptz[0].c_str(), wide[0].c_str(), m[0].str().c_str());

  // The wide head's stream: the robot sends it, the server receives it beside the PTZ head's.
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(wide stream: on, sim:\S+ 480x360 @ 15 fps, \S+ 800 kbit/s)"))) << out;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(wide received: ([0-9.]+) fps, decoded ([0-9.]+) fps)"))) << out;
  EXPECT_GE(std::stod(m[2]), 8.0) << "15 fps captured: " << m[0];
  EXPECT_NE(out.find("robot1.wide.sdp"), std::string::npos) << "its own SDP for players: " << out;
  EXPECT_NE(out.find("robot1: video wide keyframe accepted"), std::string::npos) << out;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(robot1: snapshot (\S+robot1\.wide_1\.png))"))) << out;
  EXPECT_GT(std::filesystem::file_size(m[1].str()), 10000u) << "a 480x360 picture: " << m[1];

  // Live: the Foxglove client got the pictures (decodable from the first
  // keyframe) and the boxes, each on the picture it was found in.
  const std::string live = readFile(s.dir() / "live.json");
  std::printf("live: %s", live.c_str());
  ASSERT_TRUE(std::regex_search(live, m, std::regex(R"re("frames":([0-9]+),"keyframes":([0-9]+),"frames_decoded":([0-9]+),"frame_id":"robot1/camera_wide","annotations":([0-9]+),"boxes":([0-9]+),"on_a_picture":([0-9]+))re")))
      << live << readFile(s.dir() / "node.err");
  const int frames = std::stoi(m[1]), decoded = std::stoi(m[3]), notes = std::stoi(m[4]), boxes = std::stoi(m[5]),
            paired = std::stoi(m[6]);
  EXPECT_GE(frames, 30) << "15 fps for at least 3 s: " << live;
  EXPECT_GE(std::stoi(m[2]), 1) << live;
  EXPECT_GE(decoded, frames / 2) << "from the first keyframe on: " << live;
  EXPECT_GE(notes, 8) << "about 4 detected pictures a second: " << live;
  EXPECT_GE(boxes, notes * 7 / 10) << live;
  EXPECT_GE(paired, notes * 8 / 10) << "Foxglove pairs a box with the picture of the same time: " << live;
  EXPECT_NE(live.find("\"person +4"), std::string::npos) << "the label of the person at +45 degrees: " << live;

  // Recorded: run.mcap has the wide head's pictures and boxes (read by @mcap/core).
  const std::string mcap = recordedMcap(s);
  ASSERT_FALSE(mcap.empty()) << out;
  const std::string json = captureOutput(std::string("node ") + reader +
                                         " --decode --annotations /robot1/camera_wide_people /robot1/camera_wide " + mcap);
  ASSERT_TRUE(std::regex_search(json, m, std::regex(R"("messages":([0-9]+),"boxes":([0-9]+),"on_a_picture":([0-9]+))")))
      << json;
  EXPECT_GE(std::stoi(m[1]), 8) << json;
  EXPECT_GE(std::stoi(m[2]), std::stoi(m[1]) * 7 / 10) << json;
  EXPECT_GE(std::stoi(m[3]), std::stoi(m[1]) - 1) << json;
  ASSERT_TRUE(std::regex_search(json, m, std::regex(R"re("/robot1/camera_wide":([0-9]+))re"))) << json;
  EXPECT_GE(std::stoi(m[1]), 50) << "15 fps for the 5 s recorded: " << json;
  std::printf("recorded: %s\n", json.c_str());
}

TEST(PerceptionStack, NobodyAheadThePtzHeadLooksAsideAtASonarTrackAndTurnsBack) {
  // docs/human-awareness.md, "Active looking": a person steps up to 4.5 m
  // to the robot's left and stands there facing it, beyond the wide head's
  // view and within the left sonar's reach; nobody is ahead. With active_look on, the PTZ head turns to the
  // sonar track no head has settled, its detector finds the person there,
  // and the head turns back ahead by itself.
  Stack s("lookaside");
  std::string behavior = readFile(srcPath("config/behavior.yaml"));
  const std::string off = "active_look:                # the PTZ head";
  const auto at = behavior.find(off);
  ASSERT_NE(at, std::string::npos) << "config/behavior.yaml's active_look: block";
  const auto enabled = behavior.find("  enabled: false", at);
  ASSERT_NE(enabled, std::string::npos) << "active_look.enabled";
  behavior.replace(enabled, 16, "  enabled: true");
  const auto fis = behavior.find("config/fuzzy/");  // relative to the source tree
  ASSERT_NE(fis, std::string::npos) << "awareness.speed_fis";
  behavior.replace(fis, 13, srcPath("config/fuzzy/"));
  writeFile(s.dir() / "behavior.yaml", behavior);
  const std::string out =
      runWithCamera(s, "lookaside",
                    "name: one_person_left\nstart: {x_m: 0, y_m: 0, theta_rad: 0}\n"
                    "walls:\n  - {points_m: [-6, -6,  12, -6,  12, 6,  -6, 6], closed: true}\n"
                    "pedestrians:\n  - {id: p, speed_m_s: 0.5, route_m: [0.0, 4.6, 0.0, 4.5]}\n",
                    "expect robots >= 1 within 20\n"
                                        "wait 6\n"
                    "video stats\n"
                    "status\n",
                    {.client_args = {"--behavior-config", s.dir() / "behavior.yaml"}});
  const auto lines = peopleLines(out);
  ASSERT_EQ(lines.size(), 1u) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(lines[0], m, std::regex(R"(([0-9]+) looks aside \(([0-9.]+) s off the path\))")))
      << lines[0] << "\n" << s.logs();
  EXPECT_GE(std::stoi(m[1]), 1) << lines[0];
  const double off_path_s = std::stod(m[2]);
  EXPECT_GT(off_path_s, 0.2) << lines[0];
  EXPECT_LT(off_path_s, 4.0) << "one look of ~1.2 s (turn, dwell), a second after the 6 s revisit at most: " << lines[0];
  const std::string client_log = readFile(s.dir() / "robot1-client.err");
  ASSERT_TRUE(std::regex_search(client_log, m, std::regex(R"(the camera looks aside at sonar track [0-9]+, pan ([-0-9.]+) rad)")))
      << client_log;
  // The person from the PTZ lens (0.2 m ahead of the axle): atan2(4, -0.2).
  EXPECT_NEAR(std::stod(m[1]), std::atan2(4.5, -0.2), 0.15) << client_log;
  ASSERT_TRUE(std::regex_search(client_log, m, std::regex(R"(is over \(([^)]*)\): the camera goes back ahead)")))
      << client_log;
  const std::string outcome = m[1];
  // The look was settled by the PTZ head's pictures. Facing the robot, the person is found
  // (8 runs of 9, one beside two other stack tests not); seen side-on, HOG misses them and the
  // one miss doubts the track ("nobody seen there: not a person").
  EXPECT_TRUE(outcome == "a person found there" || outcome == "nobody seen there: not a person") << client_log;
  std::printf("%s\nthe look: %s\n", lines[0].c_str(), outcome.c_str());
}
