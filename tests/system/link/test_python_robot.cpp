// A robot written in Python from proto/ alone (tests/tools/python_robot.py,
// protoc's own Python module) against the real pc_server over mutual TLS:
// the link protocol 2's presence rule as a user of another language meets it
// (docs/link-protocol.md "Presence"). Fields it leaves out are shown as
// unknown, not 0; fields it sends as 0 are 0; a version-1 robot is told what
// is wrong.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"

using namespace inspect::test;

namespace {

std::string pythonProtoDir() {
  const char* d = std::getenv("INSPECT_PYTHON_PROTO");
  return d ? d : binDir() + "/../python_proto";
}

// Runs the Python robot against `s`'s server; returns its exit status and
// leaves its output in <dir>/python_robot.out.
std::optional<int> runPythonRobot(Stack& s, const std::vector<std::string>& extra, double seconds) {
  // Debian's Python, which has python3-protobuf (scripts/setup.sh), whatever else is first in PATH.
  std::vector<std::string> argv = {"/usr/bin/python3", srcPath("tests/tools/python_robot.py"),
                                   "--port", std::to_string(s.port()), "--certs", testCertsDir({"robot1"}),
                                   "--id", "robot1", "--seconds", std::to_string(seconds),
                                   "--pb-dir", pythonProtoDir()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  auto robot = Process::spawn(argv, s.dir() / "python_robot.out", s.dir() / "python_robot.out");
  return robot.wait(seconds + 20);
}

// The server runs `script` while the Python robot runs for `seconds`; both
// must end well. Returns the server's output ("" after a failure).
std::string runScriptWithPythonRobot(Stack& s, const std::string& script, const std::vector<std::string>& extra,
                                     double seconds) {
  EXPECT_TRUE(s.startServer(script)) << s.logs();
  const auto rc = runPythonRobot(s, extra, seconds);
  EXPECT_EQ(rc, std::optional<int>(0)) << readFile(s.dir() / "python_robot.out");
  const auto server_rc = s.server().wait(30);
  EXPECT_EQ(server_rc, std::optional<int>(0)) << s.logs();
  return s.serverOutput();
}

const char* kConnected = "expect robots >= 1 within 15\nexpect x ~ 1.0 0.001 within 5\n";

}  // namespace

TEST(PythonRobot, FieldsLeftOutAreUnknownNotZero) {
  Stack s("pyrobot");
  testCertsDir({"robot1"});
  std::string script = kConnected;
  for (const char* f : {"person_m", "speed_factor", "people", "v", "w", "wheel_l", "battery", "sensor_hz", "pos_err",
                        "kp", "goal_dist", "dwell", "gas0"})
    script += std::string("expect ") + f + " == unknown\n";
  // No comparison with a number holds for an unknown field.
  script += "try expect person_m >= 0\ntry expect speed_factor ~ 0 1\nstatus\n";
  script += "expect robots == 0 within 20\n";  // the robot's whole run
  const std::string out = runScriptWithPythonRobot(s, script, {}, 6);
  std::printf("%s", out.c_str());
  EXPECT_NE(out.find("person_m = unknown, wanted >= 0"), std::string::npos) << out;
  EXPECT_NE(out.find("speed_factor = unknown, wanted ~ 0 +- 1"), std::string::npos) << out;
  // The status line says unknown where the robot said nothing, and never a person at 0 m.
  EXPECT_NE(out.find("| v unknown w unknown |"), std::string::npos) << out;
  EXPECT_NE(out.find("| people unknown"), std::string::npos) << out;
  EXPECT_NE(out.find("| bat unknown"), std::string::npos) << out;
  EXPECT_EQ(out.find("person 0.0 m"), std::string::npos) << out;
  EXPECT_EQ(out.find("speed x0.00"), std::string::npos) << out;
  // Only the two `try` lines failed: every `== unknown` held.
  std::size_t failed = 0;
  for (std::size_t p = out.find("EXPECT FAILED"); p != std::string::npos; p = out.find("EXPECT FAILED", p + 1)) ++failed;
  EXPECT_EQ(failed, 2u) << out;
}

TEST(PythonRobot, FieldsSentAsZeroAreZero) {
  Stack s("pyrobot0");
  testCertsDir({"robot1"});
  std::string script = kConnected;
  script += "expect person_m == 0\nexpect speed_factor == 0\nexpect v == 0\nexpect battery == 0\nexpect people == 0\n"
            "expect person_m != unknown\nstatus\nexpect robots == 0 within 20\n";
  const std::string out = runScriptWithPythonRobot(s, script, {"--send-zeros"}, 5);
  EXPECT_NE(out.find("person 0.0 m ? speed x0.00"), std::string::npos) << out;
  EXPECT_NE(out.find("| bat 0.0 V"), std::string::npos) << out;
}

TEST(PythonRobot, AnOldProtocolVersionIsToldWhatIsWrong) {
  Stack s("pyrobot1");
  testCertsDir({"robot1"});
  ASSERT_TRUE(s.startServer("wait 30\n")) << s.logs();
  const auto rc = runPythonRobot(s, {"--protocol-version", "1"}, 2);
  ASSERT_TRUE(rc.has_value());
  EXPECT_EQ(*rc, 3) << readFile(s.dir() / "python_robot.out");
  const std::string said = readFile(s.dir() / "python_robot.out");
  EXPECT_NE(said.find("accepted=False"), std::string::npos) << said;
  EXPECT_NE(said.find("protocol version mismatch: robot speaks 1, server speaks 2; update the robot"), std::string::npos)
      << said;
  s.server().terminate();
}
