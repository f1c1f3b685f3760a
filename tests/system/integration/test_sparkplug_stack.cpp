// The plant's SCADA sees the robot's gas alarms (docs/sparkplug.md): the real
// pc_server as a Sparkplug B edge node on a real mosquitto (its own port,
// password file), a robot driving through the gas lab's CH4 plume, and a
// Sparkplug host written from the specification in Python
// (tests/tools/sparkplug_host.py, python3-paho-mqtt and protoc's module of
// the project's sparkplug_b.proto) as the primary host, which asks for a
// rebirth once. The broker is killed for 10 s mid-run: every alarm
// transition the console lists reaches the host once, in order, with the
// robot's time; births, seq and bdSeq keep the specification's rules
// throughout.
#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support/mosquitto_broker.hpp"
#include "tests/support/sparkplug_host.hpp"
#include "tests/support/paths.hpp"
#include "tests/support/stack.hpp"
#include "tests/support/test_certs.hpp"

using namespace inspect::test;

namespace {
int count(const std::string& s, const std::string& what) {
  int n = 0;
  for (auto p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

/// The Python Sparkplug host as primary host `scada1` on `broker` (more
/// arguments in `extra`), subscribed, and <dir>/server.yaml: the shipped
/// config with its sparkplug: block on that broker and `set`.
Process startHostAndConfig(Stack& s, const MosquittoBroker& broker, std::vector<std::string> extra,
                           const std::vector<std::pair<std::string, std::string>>& set) {
  extra.push_back("--until-ndeath");
  auto host = startSparkplugHost(broker, s.dir().path(), "scada1", extra);
  writeFile(s.dir() / "server.yaml", sparkplugServerConfig(srcPath("config/server.yaml"), broker, "scada1", set));
  return host;
}
}  // namespace

TEST(SparkplugStack, AlarmsReachTheScadaHostOnceInOrderThroughABrokerOutage) {
  Stack s("sparkplug");
  MosquittoBroker broker(s.dir().path());
  const std::string host_json = sparkplugHostJson(s.dir().path());
  // The host asks for a rebirth (NCMD Node Control/Rebirth) 4 s in, before the outage.
  auto host = startHostAndConfig(s, broker, {"--seconds", "90", "--rebirth-after", "4"},
                                 {{"min_period_s", "0.2"}, {"edge_node_id", "ops1"}});
  ASSERT_TRUE(s.startServer("expect robots >= 1 within 20\n"
                            "drive 0.35 0\n"
                            "wait 24\n"
                            "stop\n"
                            "wait 3\n"
                            "alarms all\n",
                            {"--config", s.dir() / "server.yaml", "--no-record"}))
      << s.logs();
  s.startRobot("robot1", "gas_lab.yaml");
  // The broker crashes 8 s into the drive and is back 10 s later (the plume is met meanwhile).
  ASSERT_TRUE(waitUntil([&] { return s.serverOutput().find("drive 0.35") != std::string::npos; }, 30.0)) << s.logs();
  std::this_thread::sleep_for(std::chrono::seconds(8));
  broker.kill();
  std::this_thread::sleep_for(std::chrono::seconds(10));
  broker.start();
  const auto rc = s.server().wait(60.0);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  const auto host_rc = host.wait(20.0);
  ASSERT_EQ(host_rc, std::optional<int>(0)) << readFile(s.dir() / "sparkplug_host.out");
  const std::string out = s.serverOutput(), json = readFile(host_json);
  std::printf("%s\n%s\n", readFile(s.dir() / "sparkplug_host.out").c_str(), json.c_str());
  const auto host_out = nlohmann::json::parse(json);
  EXPECT_TRUE(host_out["violations"].empty()) << json;
  EXPECT_EQ(host_out["node_births"].get<int>(), 3) << "the first, the rebirth asked, after the outage: " << json;
  EXPECT_NE(readFile(s.dir() / "server.err").find("NCMD Node Control/Rebirth: the births again"), std::string::npos)
      << s.logs();
  EXPECT_EQ(host_out["ndeaths"].get<int>(), 1) << "the clean NDEATH at the end";

  // The console's alarm book: "#1 robot1 CH4 LOW ... raised 14.5 s ago, cleared after 12.0 s".
  const std::regex book(R"(#([0-9]+) robot1 ([A-Z0-9]+) (LOW|HIGH) [^\n]*raised [0-9.]+ s ago, cleared after ([0-9.]+) s)");
  struct Alarm {
    std::string metric;
    double lasted_s;
  };
  std::map<int, Alarm> alarms;
  for (std::sregex_iterator it(out.begin(), out.end(), book), end; it != end; ++it)
    alarms[std::stoi((*it)[1])] = {"Gas/" + (*it)[2].str() + ((*it)[3] == "LOW" ? "/A1" : "/A2"), std::stod((*it)[4])};
  ASSERT_GE(alarms.size(), 1u) << "the plume raised and cleared no alarm: " << out;
  // Each transition reached the host exactly once, under its level's metric, in the robot's order.
  std::map<std::pair<int, bool>, int> seen;
  std::map<std::pair<int, bool>, double> at_ms;
  double last_ms = 0;
  int historical = 0;
  for (const auto& a : host_out["alarms"]) {
    const int id = a["id"].get<int>();
    const bool active = a["active"].get<bool>();
    ++seen[{id, active}];
    at_ms[{id, active}] = a["timestamp_ms"].get<double>();
    EXPECT_GE(a["timestamp_ms"].get<double>(), last_ms) << "in the robot's order: " << json;
    last_ms = a["timestamp_ms"].get<double>();
    historical += a["historical"].get<bool>() ? 1 : 0;
    ASSERT_TRUE(alarms.count(id)) << "an alarm the console does not list: " << json;
    EXPECT_EQ(a["metric"].get<std::string>(), alarms[id].metric) << json;
  }
  for (const auto& [id, a] : alarms) {
    EXPECT_EQ((seen[{id, true}]), 1) << "raise of #" << id << ": " << json;
    EXPECT_EQ((seen[{id, false}]), 1) << "clear of #" << id << ": " << json;
    // The robot's times: the clear after the raise by what the console says (0.1 s rounding, 20 ms ticks).
    EXPECT_NEAR((at_ms[{id, false}] - at_ms[{id, true}]) / 1000.0, a.lasted_s, 0.15) << "#" << id;
  }
  EXPECT_EQ(host_out["alarms"].size(), 2 * alarms.size()) << json;
  std::printf("%zu alarms, %zu transitions at the host, %d of them historical (held through the outage)\n",
              alarms.size(), host_out["alarms"].size(), historical);
}

TEST(SparkplugStack, ScadaMayStopAndEStopARobotButNeverMoveItOverTls) {
  // docs/sparkplug.md "Commands": with sparkplug.commands on, the host's DCMD
  // Commands/E-Stop e-stops the robot through an operator session of its own
  // (which needs no control to stop); a metric that is not a command is
  // refused; both are answered in DDATA (Commands/Last Result). The robot
  // stays e-stopped: resuming is the operator's.
  // Over TLS both ways: the broker's certificate of the test CA (127.0.0.1 in
  // it) and a client certificate each for the edge node and the host.
  Stack s("sparkplug-dcmd");
  const std::string certs = testCertsDir({"robot1", "scada-edge", "scada-host"});
  MosquittoBroker broker(s.dir().path(), {certs + "/ca.pem", certs + "/server.pem", certs + "/server.key"});
  const std::string host_json = sparkplugHostJson(s.dir().path());
  auto host = startHostAndConfig(
      s, broker,
      {"--seconds", "60", "--dcmd", "1:robot1:Commands/Drive", "--dcmd", "2:robot1:Commands/E-Stop", "--tls",
       certs + "/ca.pem", certs + "/scada-host.pem", certs + "/scada-host.key"},
      {{"commands", "true"}, {"min_period_s", "0.2"}, {"ca", certs + "/ca.pem"}, {"cert", certs + "/scada-edge.pem"},
       {"key", certs + "/scada-edge.key"}});
  ASSERT_TRUE(s.startServer("expect robots >= 1 within 20\n"
                            "drive 0.2 0\n"
                            "expect mode == ESTOP within 20\n"
                            "wait 2\n"
                            "expect mode == ESTOP\n"
                            "expect v ~ 0 0.02\n",
                            {"--config", s.dir() / "server.yaml", "--no-record"}))
      << s.logs();
  s.startRobot("robot1");
  const auto rc = s.server().wait(60.0);
  ASSERT_TRUE(rc.has_value()) << s.logs();
  EXPECT_EQ(*rc, 0) << s.serverOutput() << s.logs();
  ASSERT_EQ(host.wait(20.0), std::optional<int>(0)) << readFile(s.dir() / "sparkplug_host.out");
  const auto out = nlohmann::json::parse(readFile(host_json));
  std::printf("%s\n", out["answers"].dump(1).c_str());
  EXPECT_TRUE(out["violations"].empty()) << out.dump(1);
  ASSERT_EQ(out["answers"].size(), 2u) << out.dump(1);
  EXPECT_NE(out["answers"][0]["text"].get<std::string>().find("refused: 'Commands/Drive' is not a command SCADA may give"),
            std::string::npos)
      << out["answers"][0];
  EXPECT_EQ(out["answers"][1]["text"].get<std::string>(), "robot1: estop accepted") << out["answers"][1];
  EXPECT_NE(readFile(s.dir() / "server.err").find("DCMD from SCADA: robot1 e-stop"), std::string::npos) << s.logs();
}
