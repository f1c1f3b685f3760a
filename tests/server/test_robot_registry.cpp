// The robot registry: replaced sessions cannot write, bounded histories, selection order.
#include <gtest/gtest.h>

#include "pc_server/robot_registry.hpp"

using namespace inspect;
using namespace inspect::server;

namespace {
constexpr int64_t kSec = 1'000'000'000;

v1::Hello hello(const std::string& id) {
  v1::Hello h;
  h.set_robot_id(id);
  return h;
}
}  // namespace

TEST(RobotRegistry, OlderSessionCannotOverwriteItsReplacement) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  reg.onConnected("r", "a:2", 2, hello("r"), kSec);
  v1::Telemetry t;
  t.mutable_pose()->set_x_m(5);
  reg.onTelemetry("r", 1, t, kSec);  // from the replaced connection
  reg.onDisconnected("r", 1, "replaced", kSec);
  auto s = reg.snapshot("r", kSec);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->connected);
  EXPECT_FALSE(s->has_telemetry);
  EXPECT_EQ(s->address, "a:2");
  reg.onDisconnected("r", 2, "gone", 2 * kSec);
  s = reg.snapshot("r", 3 * kSec);
  EXPECT_FALSE(s->connected);
  EXPECT_EQ(s->close_reason, "gone");
  EXPECT_DOUBLE_EQ(s->state_age_s, 1.0);
}

TEST(RobotRegistry, AcksAndEventsAreBounded) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  for (uint64_t id = 1; id <= RobotRegistry::kMaxAcksPerRobot + 50; ++id) {
    v1::Ack a;
    a.set_command_id(id);
    a.set_status(v1::Ack::ACCEPTED);
    reg.onAck("r", 1, a);
  }
  EXPECT_FALSE(reg.ack("r", 50)) << "the oldest acks are dropped";
  EXPECT_TRUE(reg.ack("r", 51));
  EXPECT_TRUE(reg.ack("r", RobotRegistry::kMaxAcksPerRobot + 50));
  for (std::size_t i = 0; i < RobotRegistry::kMaxPendingEvents + 10; ++i) {
    v1::Event e;
    e.set_text(std::to_string(i));
    reg.onEvent("r", 1, e);
  }
  EXPECT_EQ(reg.events("r").size(), RobotRegistry::kMaxEventsPerRobot);
  EXPECT_EQ(reg.events("r").back().text(), std::to_string(RobotRegistry::kMaxPendingEvents + 9));
  EXPECT_EQ(reg.takeEvents().size(), RobotRegistry::kMaxPendingEvents);
  EXPECT_EQ(reg.droppedEvents(), 10u);
  EXPECT_TRUE(reg.takeEvents().empty());
}

TEST(RobotRegistry, TelemetryRateOverTheLastSecond) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  v1::Telemetry t;
  for (int i = 1; i <= 100; ++i) reg.onTelemetry("r", 1, t, i * kSec / 50);  // 50 Hz for 2 s
  auto s = reg.snapshot("r", 2 * kSec);
  EXPECT_NEAR(s->telemetry_hz, 50.0, 1.0);
  EXPECT_EQ(s->telemetry_count, 100u);
  s = reg.snapshot("r", 4 * kSec);
  EXPECT_EQ(s->telemetry_hz, 0.0) << "no telemetry for 2 s";
  EXPECT_DOUBLE_EQ(s->telemetry_age_s, 2.0);
}

TEST(RobotRegistry, FirstConnectedIsByConnectionOrder) {
  RobotRegistry reg;
  EXPECT_EQ(reg.firstConnected(), "");
  reg.onConnected("zeta", "a:1", 1, hello("zeta"), 0);
  reg.onConnected("alpha", "a:2", 2, hello("alpha"), 0);
  EXPECT_EQ(reg.firstConnected(), "zeta");
  EXPECT_EQ(reg.connectedCount(), 2);
  reg.onDisconnected("zeta", 1, "bye", 0);
  EXPECT_EQ(reg.firstConnected(), "alpha");
  EXPECT_EQ(reg.connectedCount(), 1);
  EXPECT_EQ(reg.snapshots(0).size(), 2u);
}
