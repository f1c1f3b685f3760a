// The robot registry: replaced sessions cannot write, bounded histories, selection order.
#include <gtest/gtest.h>

#include "pc_server/link/robot_registry.hpp"

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

// ---- The gas alarm book ----

namespace {
v1::Event alarmEvent(uint64_t id, const std::string& ch, v1::GasAlarm::Level level, bool active, double value) {
  v1::Event e;
  e.set_kind(active ? v1::Event::ALARM_RAISED : v1::Event::ALARM_CLEARED);
  auto* a = e.mutable_gas_alarm();
  a->set_id(id);
  a->set_channel_name(ch);
  a->set_level(level);
  a->set_active(active);
  a->set_value(value);
  a->set_peak(value);
  a->set_unit("ppm");
  return e;
}
}  // namespace

TEST(RobotRegistryAlarms, RaiseUpdateClearAndAcknowledge) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  auto raise = alarmEvent(7, "H2S", v1::GasAlarm::HIGH, true, 11.0);
  raise.mutable_gas_alarm()->mutable_pose()->set_x_m(2.5);
  reg.onEvent("r", 1, raise, kSec);
  auto list = reg.alarms(false);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].number, 1);
  EXPECT_TRUE(list[0].active());
  EXPECT_EQ(reg.unackedAlarms(), 1);
  // Telemetry carries the reading now and the worst so far.
  v1::Telemetry t;
  auto* a = t.add_active_alarms();
  *a = alarmEvent(7, "H2S", v1::GasAlarm::HIGH, true, 14.0).gas_alarm();
  reg.onTelemetry("r", 1, t, 2 * kSec);
  list = reg.alarms(false);
  ASSERT_EQ(list.size(), 1u) << "the same alarm, not a new one";
  EXPECT_DOUBLE_EQ(list[0].alarm.peak(), 14.0);
  reg.onEvent("r", 1, alarmEvent(7, "H2S", v1::GasAlarm::HIGH, false, 8.0), 5 * kSec);
  list = reg.alarms(false);
  ASSERT_EQ(list.size(), 1u) << "cleared but unacknowledged: still listed";
  EXPECT_FALSE(list[0].active());
  EXPECT_EQ(list[0].cleared_ns - list[0].raised_ns, 4 * kSec);
  EXPECT_DOUBLE_EQ(list[0].alarm.pose().x_m(), 2.5) << "where it was raised, not where it cleared";
  EXPECT_DOUBLE_EQ(list[0].alarm.value(), 8.0) << "the reading at the clear";
  EXPECT_EQ(reg.unackedAlarms(), 0) << "only active ones count";
  const auto acked = reg.ackAlarm(1, 6 * kSec);
  ASSERT_TRUE(acked);
  EXPECT_TRUE(acked->acked);
  EXPECT_TRUE(reg.alarms(false).empty());
  EXPECT_EQ(reg.alarms(true).size(), 1u);
  EXPECT_FALSE(reg.ackAlarm(2, 6 * kSec));
}

TEST(RobotRegistryAlarms, TelemetryResyncsMissedRaisesAndClears) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  v1::Telemetry t;
  *t.add_active_alarms() = alarmEvent(3, "CH4", v1::GasAlarm::LOW, true, 12.0).gas_alarm();
  reg.onTelemetry("r", 1, t, kSec);  // the raise event was lost (e.g. the server restarted)
  ASSERT_EQ(reg.alarms(false).size(), 1u);
  const auto ev = reg.takeEvents();  // ...and the console still hears of it
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].event.kind(), v1::Event::ALARM_RAISED);
  EXPECT_NE(ev[0].event.text().find("gas CH4 LOW alarm in force (learnt from telemetry"), std::string::npos)
      << ev[0].event.text();
  reg.onTelemetry("r", 1, t, kSec + 1000);
  EXPECT_EQ(reg.alarms(true).size(), 1u) << "known by id: not added twice";
  t.clear_active_alarms();
  reg.onTelemetry("r", 1, t, 3 * kSec);  // and its clear was lost too
  const auto list = reg.alarms(true);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_FALSE(list[0].active());
  // A clear of an alarm never seen raised is ignored.
  reg.onEvent("r", 1, alarmEvent(99, "CO", v1::GasAlarm::HIGH, false, 1.0), 4 * kSec);
  EXPECT_EQ(reg.alarms(true).size(), 1u);
  EXPECT_EQ(reg.ackAllAlarms(5 * kSec).size(), 1u);
  EXPECT_TRUE(reg.ackAllAlarms(5 * kSec).empty());
}

TEST(RobotRegistryAlarms, TheBookIsBoundedButKeepsActiveAlarms) {
  RobotRegistry reg;
  reg.onConnected("r", "a:1", 1, hello("r"), 0);
  reg.onEvent("r", 1, alarmEvent(1, "CH4", v1::GasAlarm::HIGH, true, 30.0), 0);  // stays active
  for (uint64_t id = 2; id < RobotRegistry::kMaxAlarms + 50; ++id) {
    reg.onEvent("r", 1, alarmEvent(id, "H2S", v1::GasAlarm::LOW, true, 6.0), static_cast<int64_t>(id));
    reg.onEvent("r", 1, alarmEvent(id, "H2S", v1::GasAlarm::LOW, false, 3.0), static_cast<int64_t>(id) + 1);
  }
  const auto all = reg.alarms(true);
  EXPECT_EQ(all.size(), RobotRegistry::kMaxAlarms);
  EXPECT_EQ(all.front().number, 1) << "the active alarm is never dropped";
  EXPECT_TRUE(all.front().active());
}
