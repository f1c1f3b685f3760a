// The Foxglove bridge through the real programs (mcu_sim, robot_client with
// its camera, pc_server with the bridge on an ephemeral port and a token):
// tests/tools/foxglove_client.js, with the Foxglove client library
// (@foxglove/ws-protocol over ws) and protobufjs, subscribes to every channel,
// decodes everything with the advertised schemas, measures the rates, drives
// the robot by teleop (seen in mcu_sim's ground truth), calls services, is
// refused motion without control and refused without the token, and sends
// bad input. The server's `foxglove` command then shows the clients.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "tests/support/stack.hpp"

using namespace inspect::test;

TEST(FoxgloveStack, ClientLibraryDecodesDrivesCallsAndIsRefused) {
  const char* reader = std::getenv("INSPECT_NODE_MODULES");
  ASSERT_NE(reader, nullptr) << "INSPECT_NODE_MODULES (the npm fixture's folder) is not set";
  Stack s("foxglove");
  s.enableVideo();
  s.enableFoxglove();
  writeFile(s.dir() / "server.yaml", "video:\n  window: off\n  forward_base_port: 0\n");
  ASSERT_TRUE(s.startServer("expect robots >= 1 within 20\n"
                            "expect sensor_hz > 50 within 5\n"
                            "wait 10\n"
                            "foxglove\n"
                            "wait 30\n",
                            {"--config", s.dir() / "server.yaml", "--site-map", srcPath("config/worlds/square_room.yaml")}))
      << s.logs();
  auto& r = s.startRobot("robot1");
  // The client looks for the robot's channels for 5 s once connected: start it when the robot is
  // (on a loaded host robot_client once took 20 s to come up, and the client found no channel).
  EXPECT_TRUE(waitUntil([&] { return s.serverOutput().find("expect ok (line 1)") != std::string::npos; }, 30.0))
      << "the robot did not connect within 30 s\n" << s.logs();
  const std::string url = "ws://127.0.0.1:" + std::to_string(s.foxglovePort()) + "/";
  auto node = Process::spawn({"/usr/bin/env", "node", srcPath("tests/tools/foxglove_client.js"), "--modules", reader, "--url", url,
                              "--token", s.foxgloveToken(), "--truth", r.truth, "--robot", "robot1", "--seconds", "6",
                              "--layout", srcPath("config/foxglove/inspect_live.json"),
                              "--json", s.dir() / "foxglove.json"},
                             s.dir() / "node.out", s.dir() / "node.err");
  const auto status = node.wait(100.0);
  const std::string out = readFile(s.dir() / "node.out") + readFile(s.dir() / "node.err");
  std::cout << out;
  ASSERT_TRUE(status.has_value()) << "the Foxglove client did not finish within 100 s\n" << out << s.logs();
  EXPECT_EQ(*status, 0) << out << s.logs();
  // While the first client was subscribed, the console listed it.
  const std::string server = s.serverOutput();
  EXPECT_NE(server.find("pc_server: Foxglove WebSocket on ws://127.0.0.1:"), std::string::npos) << server;
  EXPECT_NE(server.find("foxglove: ws://127.0.0.1:"), std::string::npos) << server;
  EXPECT_NE(server.find("(token required)"), std::string::npos) << server;
  EXPECT_NE(server.find("subscribed: /robot1/"), std::string::npos) << server;
  EXPECT_NE(server.find("(foxglove 127.0.0.1:"), std::string::npos) << server;  // the client's operator session
}
