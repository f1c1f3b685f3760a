// RobotCore: gains updates (validated, staged, applied at the next tick,
// versioned, announced) and the open-loop wheel test for identification.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "shared/robot/robot_core.hpp"
#include "shared/config/control_config.hpp"
#include "shared/net/gains_proto.hpp"
#include "tests/support/paths.hpp"
#include "tests/robot/core_harness.hpp"

using namespace inspect;
using robot::RobotCore;

namespace {

// The core with the project's control config (the paper's fuzzy-PID).
struct TunedHarness : inspect::test::CoreHarness {
  TunedHarness() : CoreHarness(config::loadControlConfigFile(inspect::test::srcPath("config/control.yaml"))) {}
};

v1::Command gainsCmd(uint64_t id, const control::GainSet& g, const std::string& fis = "") {
  v1::Command c;
  c.set_id(id);
  net::toProto(g, *c.mutable_gains()->mutable_gains());
  c.mutable_gains()->set_fis(fis);
  c.mutable_gains()->set_source("test");
  return c;
}

v1::Command wheelTest(uint64_t id, std::initializer_list<std::tuple<const char*, double, double, double>> segs) {
  v1::Command c;
  c.set_id(id);
  c.mutable_wheel_test()->set_name("idtest");
  for (const auto& [kind, d, l, r] : segs) {
    auto* s = c.mutable_wheel_test()->add_segments();
    s->set_kind(kind);
    s->set_duration_s(d);
    s->set_left_rad_s(l);
    s->set_right_rad_s(r);
  }
  return c;
}

std::string readFile(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

TEST(RobotCoreGains, UpdateIsStagedAppliedAtTheNextTickAndVersioned) {
  TunedHarness h;
  h.run(0.05);
  EXPECT_EQ(h.core.gainsVersion(), 0u);
  EXPECT_DOUBLE_EQ(h.core.gains().fuzzy.base.kp, 9.0) << "config/control.yaml's kp'";
  control::GainSet g = h.core.gains();
  g.fuzzy.base.kp = 4.5;
  g.aux.a3 = -0.8;
  const auto ack = h.core.onCommand(gainsCmd(1, g), h.t);
  ASSERT_EQ(ack.status(), v1::Ack::ACCEPTED) << ack.reason();
  EXPECT_EQ(ack.gains_version(), 1u);
  // Not yet in force: the tick boundary applies it.
  EXPECT_EQ(h.core.gainsVersion(), 0u);
  EXPECT_DOUBLE_EQ(h.core.gains().fuzzy.base.kp, 9.0);
  h.step();
  EXPECT_EQ(h.core.gainsVersion(), 1u);
  EXPECT_DOUBLE_EQ(h.core.gains().fuzzy.base.kp, 4.5);
  EXPECT_DOUBLE_EQ(h.core.gains().aux.a3, -0.8);
  v1::Telemetry t;
  h.core.fillTelemetry(t, h.t);
  EXPECT_EQ(t.gains_version(), 1u);
  bool announced = false;
  for (const auto& e : h.core.takeEvents())
    if (e.kind == v1::Event::GAINS_APPLIED) {
      announced = true;
      ASSERT_TRUE(e.gains.has_value());
      EXPECT_EQ(e.gains_version, 1u);
      EXPECT_DOUBLE_EQ(e.gains->kp(), 4.5);
      EXPECT_NE(e.text.find("gains v1 in force"), std::string::npos) << e.text;
    }
  EXPECT_TRUE(announced);
  // Two updates between ticks: both acked with increasing versions, the later one is in force.
  g.fuzzy.base.ki = 1.0;
  EXPECT_EQ(h.core.onCommand(gainsCmd(2, g), h.t).gains_version(), 2u);
  g.fuzzy.base.ki = 1.5;
  EXPECT_EQ(h.core.onCommand(gainsCmd(3, g), h.t).gains_version(), 3u);
  h.step();
  EXPECT_EQ(h.core.gainsVersion(), 3u);
  EXPECT_DOUBLE_EQ(h.core.gains().fuzzy.base.ki, 1.5);
}

TEST(RobotCoreGains, BadGainsAreRejectedWithTheReasonAndChangeNothing) {
  TunedHarness h;
  h.run(0.05);
  control::GainSet g = h.core.gains();
  g.fuzzy.base.kd = std::nan("");
  auto ack = h.core.onCommand(gainsCmd(1, g), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("kd = nan is not finite"), std::string::npos) << ack.reason();
  EXPECT_EQ(ack.gains_version(), 0u) << "the version still in force";
  g = h.core.gains();
  g.aux.a2 = 0.5;
  ack = h.core.onCommand(gainsCmd(2, g), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("a2 = 0.5 is outside [-20, 0]"), std::string::npos) << ack.reason();
  g = h.core.gains();
  ack = h.core.onCommand(gainsCmd(3, g, "[System]\nName='broken'\nNumInputs=7\n"), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("fuzzy system refused"), std::string::npos) << ack.reason();
  v1::Command empty;
  empty.set_id(4);
  empty.mutable_gains();
  EXPECT_EQ(h.core.onCommand(empty, h.t).status(), v1::Ack::REJECTED);
  h.step();
  EXPECT_EQ(h.core.gainsVersion(), 0u);
  EXPECT_DOUBLE_EQ(h.core.gains().fuzzy.base.kd, 3.0);
}

TEST(RobotCoreGains, APushedFuzzySystemReplacesTheLoadedOne) {
  TunedHarness h;
  h.run(0.05);
  const std::string fis = readFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  ASSERT_FALSE(fis.empty());
  const auto ack = h.core.onCommand(gainsCmd(1, h.core.gains(), fis), h.t);
  ASSERT_EQ(ack.status(), v1::Ack::ACCEPTED) << ack.reason();
  h.step();
  EXPECT_EQ(h.core.gainsVersion(), 1u);
  EXPECT_FALSE(h.core.fisName().empty());
}

TEST(RobotCoreGains, NewGainsReachAPathBeingTracked) {
  TunedHarness h;
  h.run(0.05);
  v1::Command c;
  c.set_id(1);
  c.mutable_track()->mutable_line()->set_length_m(3.0);
  c.mutable_track()->mutable_line()->set_speed_m_s(0.3);
  c.mutable_track()->set_controller("pid");
  ASSERT_EQ(h.core.onCommand(c, h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.5);
  v1::Telemetry t;
  h.core.fillTelemetry(t, h.t);
  EXPECT_DOUBLE_EQ(t.kp(), 9.0);
  control::GainSet g = h.core.gains();
  g.fuzzy.base = {2.0, 0.5, 0.0};
  ASSERT_EQ(h.core.onCommand(gainsCmd(2, g), h.t).status(), v1::Ack::ACCEPTED);
  h.step();
  h.step();
  h.core.fillTelemetry(t, h.t);
  EXPECT_EQ(h.core.mode(), v1::TRACKING) << "the run goes on";
  EXPECT_DOUBLE_EQ(t.kp(), 2.0) << "the PID of the running path uses the new gains";
  EXPECT_EQ(t.gains_version(), 1u);
}

TEST(RobotCoreWheelTest, PlaysTheProfileOpenLoopAndCompletes) {
  TunedHarness h;
  h.run(0.05);
  const auto ack = h.core.onCommand(wheelTest(1, {{"hold", 0.2, 0, 0}, {"step", 0.5, -1.5, 1.5}}), h.t);
  ASSERT_EQ(ack.status(), v1::Ack::ACCEPTED) << ack.reason();
  EXPECT_EQ(h.core.mode(), v1::WHEEL_TEST);
  h.run(0.1);
  EXPECT_EQ(h.last.left_mrad_s, 0);
  h.run(0.3);
  // Unslewed: the step is there at once.
  EXPECT_EQ(h.last.left_mrad_s, -1500);
  EXPECT_EQ(h.last.right_mrad_s, 1500);
  v1::Telemetry t;
  h.core.fillTelemetry(t, h.t);
  EXPECT_GT(t.wheel_test_progress(), 0.5);
  EXPECT_LT(t.wheel_test_progress(), 1.0);
  std::vector<v1::Ack> acks;
  for (int i = 0; i < 100 && acks.empty(); ++i) {
    h.step();
    acks = h.core.takeAcks();
  }
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status(), v1::Ack::COMPLETED);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  h.step();
  EXPECT_EQ(h.last.left_mrad_s, 0);
}

TEST(RobotCoreWheelTest, BadProfilesAreRejectedAndSafetyStopsIt) {
  TunedHarness h;
  h.run(0.05);
  auto ack = h.core.onCommand(wheelTest(1, {{"wiggle", 1, 0, 0}}), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("unknown kind 'wiggle'"), std::string::npos) << ack.reason();
  ack = h.core.onCommand(wheelTest(2, {{"step", 1, 9.0, 0}}), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED) << "beyond the 5 rad/s wheel limit";
  EXPECT_NE(ack.reason().find("segment 1 (step)"), std::string::npos) << ack.reason();
  EXPECT_EQ(h.core.onCommand(wheelTest(3, {}), h.t).status(), v1::Ack::REJECTED);
  // Something close ahead ends it with FAILED and zero wheels.
  ASSERT_EQ(h.core.onCommand(wheelTest(4, {{"step", 5, 1, -1}}), h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.2);
  h.f.ultrasonic_mm[0] = 200;
  h.step();
  auto acks = h.core.takeAcks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status(), v1::Ack::FAILED);
  EXPECT_NE(acks[0].reason().find("obstacle 0.20 m ahead"), std::string::npos) << acks[0].reason();
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  EXPECT_EQ(h.last.left_mrad_s, 0);
  h.f.ultrasonic_mm[0] = serial::kNoEcho;
  // An e-stop ends it and latches.
  ASSERT_EQ(h.core.onCommand(wheelTest(5, {{"step", 5, 1, -1}}), h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.2);
  v1::Command e;
  e.set_id(6);
  e.mutable_estop();
  h.core.onCommand(e, h.t);
  h.step();
  EXPECT_EQ(h.core.mode(), v1::ESTOP);
  EXPECT_EQ(h.last.left_mrad_s, 0);
  EXPECT_EQ(h.last.flags, 0);
}

TEST(RobotCoreWheelTest, SpeedLimitsHoldAndTheTestStaysNearItsStart) {
  TunedHarness h;
  h.run(0.05);
  // 2.5 rad/s on both wheels is 0.5 m/s: fine; spinning at +-5 rad/s is 4.6 rad/s of yaw, above 2 rad/s.
  auto ack = h.core.onCommand(wheelTest(1, {{"step", 1, -5.0, 5.0}}), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("exceed the robot's limits"), std::string::npos) << ack.reason();
  // Driving straight on: stopped once 1 m from the start (0.5 m/s: after ~2 s).
  ASSERT_EQ(h.core.onCommand(wheelTest(2, {{"step", 10, 2.5, 2.5}}), h.t).status(), v1::Ack::ACCEPTED);
  std::vector<v1::Ack> acks;
  for (int i = 0; i < 500 && acks.empty(); ++i) {
    h.step();
    acks = h.core.takeAcks();
  }
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].status(), v1::Ack::FAILED);
  EXPECT_NE(acks[0].reason().find("m from where it began (at most 1.0 m)"), std::string::npos) << acks[0].reason();
  EXPECT_LT(h.core.pose().x_m, 1.1);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
}

TEST(RobotCoreGains, AFuzzySystemIsNotSwappedWhileMovingAndARejectionQuotesTheVersionInForce) {
  TunedHarness h;
  h.run(0.05);
  ASSERT_EQ(h.core.onCommand(wheelTest(1, {{"step", 5, -1, 1}}), h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.1);
  control::GainSet g = h.core.gains();
  // A good update is staged (v1), then a bad fuzzy system comes before the tick: refused, v0 still in force.
  ASSERT_EQ(h.core.onCommand(gainsCmd(2, g), h.t).gains_version(), 1u);
  const std::string fis = readFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  const auto ack = h.core.onCommand(gainsCmd(3, g, fis), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::REJECTED);
  EXPECT_NE(ack.reason().find("the robot is moving (WHEEL_TEST)"), std::string::npos) << ack.reason();
  EXPECT_EQ(ack.gains_version(), 0u);
  h.step();
  EXPECT_EQ(h.core.gainsVersion(), 1u);
  EXPECT_EQ(h.core.mode(), v1::WHEEL_TEST) << "gains without a fuzzy system are fine while moving";
}
