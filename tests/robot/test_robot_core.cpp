// RobotCore: modes, latches, timeouts and commands, driven with explicit time.
#include <gtest/gtest.h>

#include <cmath>

#include "shared/robot/robot_core.hpp"
#include "tests/robot/core_commands.hpp"
#include "tests/robot/core_harness.hpp"

using namespace inspect;
using robot::RobotCore;

namespace {

using test::teleop;
v1::Command simple(uint64_t id, char kind) {
  v1::Command c;
  c.set_id(id);
  if (kind == 's') c.mutable_stop();
  if (kind == 'e') c.mutable_estop();
  if (kind == 'r') c.mutable_resume();
  return c;
}

using Harness = inspect::test::CoreHarness;

}  // namespace

TEST(RobotCore, TeleopDrivesAndSlewLimits) {
  Harness h;
  ASSERT_EQ(h.core.onCommand(teleop(1, 0.5, 0.0), h.t).status(), v1::Ack::ACCEPTED);
  h.step();
  // 10 rad/s^2 * 10 ms = 0.1 rad/s per tick; the target is 2.5 rad/s.
  EXPECT_EQ(h.last.left_mrad_s, 100);
  EXPECT_EQ(h.last.flags, serial::WheelCommand::kEnable);
  for (int i = 0; i < 20; ++i) {
    h.core.onCommand(teleop(2 + i, 0.5, 0.0), h.t);
    h.run(0.05);
  }
  EXPECT_EQ(h.last.left_mrad_s, 2500);
  EXPECT_EQ(h.last.right_mrad_s, 2500);
  EXPECT_EQ(h.core.mode(), v1::TELEOP);
  EXPECT_GT(h.core.pose().x_m, 0.3);
  EXPECT_NEAR(h.core.pose().y_m, 0.0, 1e-9);
}

TEST(RobotCore, LimitsAreClampedAndSaid) {
  Harness h;
  const auto ack = h.core.onCommand(teleop(1, 9.0, 0.0), h.t);
  EXPECT_EQ(ack.status(), v1::Ack::ACCEPTED);
  EXPECT_NE(ack.reason().find("clamped"), std::string::npos);
  const auto bad = h.core.onCommand(teleop(2, std::nan(""), 0.0), h.t);
  EXPECT_EQ(bad.status(), v1::Ack::REJECTED);
}

TEST(RobotCore, StaleSetpointStopsWithin300ms) {
  Harness h;
  h.core.onCommand(teleop(1, 0.3, 0.0), h.t);
  h.run(0.29);
  EXPECT_EQ(h.core.mode(), v1::TELEOP);
  EXPECT_NE(h.last.left_mrad_s, 0);
  h.run(0.03);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  EXPECT_TRUE(h.core.faults() & v1::FAULT_COMMAND_STALE);
  // A normal stop ramps down at the wheel acceleration limit (1.5 rad/s at 10 rad/s^2: 0.15 s).
  EXPECT_LT(h.last.left_mrad_s, 1500);
  h.run(0.15);
  EXPECT_EQ(h.last.left_mrad_s, 0);
}

TEST(RobotCore, SilentLinkLatchesFailsafeUntilResume) {
  Harness h;
  for (int i = 0; i < 10; ++i) {
    h.core.onCommand(teleop(i + 1, 0.3, 0.0), h.t);
    h.run(0.05);
  }
  // Heartbeats stop; the set-point keeps being fresh only until it does not.
  h.core.onCommand(teleop(100, 0.3, 0.0), h.t);
  const double t_loss = h.t;
  while (h.core.mode() == v1::TELEOP && h.t - t_loss < 1.0) h.step(false);
  EXPECT_EQ(h.core.mode(), v1::FAILSAFE);
  EXPECT_LE(h.t - t_loss, 0.31);
  EXPECT_EQ(h.last.left_mrad_s, 0);
  EXPECT_EQ(h.last.flags, 0);  // brake
  // Link back: commands refused until resume.
  h.core.onLinkActivity(h.t);
  EXPECT_EQ(h.core.onCommand(teleop(101, 0.3, 0.0), h.t).status(), v1::Ack::REJECTED);
  EXPECT_EQ(h.core.onCommand(simple(102, 'r'), h.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  EXPECT_EQ(h.core.onCommand(teleop(103, 0.3, 0.0), h.t).status(), v1::Ack::ACCEPTED);
}

TEST(RobotCore, LinkDownWhileIdleDoesNotLatch) {
  Harness h;
  h.core.onLinkDown(h.t, "closed");
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  EXPECT_TRUE(h.core.faults() & v1::FAULT_LINK_LOST);
  h.core.onLinkUp(h.t);
  EXPECT_FALSE(h.core.faults() & v1::FAULT_LINK_LOST);
}

TEST(RobotCore, EStopIsLatched) {
  Harness h;
  h.core.onCommand(teleop(1, 0.3, 0.0), h.t);
  h.run(0.1);
  EXPECT_EQ(h.core.onCommand(simple(2, 'e'), h.t).status(), v1::Ack::ACCEPTED);
  EXPECT_EQ(h.core.commandNow().left_mrad_s, 0);
  const auto r = h.core.onCommand(teleop(3, 0.3, 0.0), h.t);
  EXPECT_EQ(r.status(), v1::Ack::REJECTED);
  EXPECT_NE(r.reason().find("e-stop"), std::string::npos);
  h.run(1.0);
  EXPECT_EQ(h.core.mode(), v1::ESTOP) << "no automatic restart";
  h.core.onCommand(simple(4, 's'), h.t);
  EXPECT_EQ(h.core.mode(), v1::ESTOP) << "stop does not clear an e-stop";
  h.core.onCommand(simple(5, 'r'), h.t);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
}

TEST(RobotCore, StaleSensorFramesStopFromTheTimer) {
  Harness h;
  h.core.onCommand(teleop(1, 0.3, 0.0), h.t);
  h.run(0.1);
  // No frames from now on; the 10 ms timer notices after sensor_timeout.
  std::optional<serial::WheelCommand> c;
  double t = h.t;
  for (int i = 0; i < 20 && !c; ++i) {
    t += 0.01;
    h.core.onLinkActivity(t);
    c = h.core.onTimer(t);
  }
  ASSERT_TRUE(c.has_value());
  EXPECT_LE(t - h.t, 0.111);
  EXPECT_EQ(c->left_mrad_s, 0);
  EXPECT_EQ(h.core.mode(), v1::FAILSAFE);
  EXPECT_EQ(h.core.onCommand(simple(2, 'r'), t).status(), v1::Ack::REJECTED) << "cannot resume while stale";
}

TEST(RobotCore, TelemetryReportsState) {
  Harness h;
  h.f.ultrasonic_mm = {1000, serial::kNoEcho, 250, 4000};
  for (int i = 0; i < 5; ++i) {
    h.core.onCommand(teleop(7, 0.2, 0.1), h.t);
    h.run(0.1);
  }
  v1::Telemetry t;
  h.core.fillTelemetry(t, h.t);
  EXPECT_EQ(t.mode(), v1::TELEOP);
  ASSERT_EQ(t.ultrasonic_m_size(), 4);
  EXPECT_DOUBLE_EQ(t.ultrasonic_m(0), 1.0);
  EXPECT_DOUBLE_EQ(t.ultrasonic_m(1), -1.0);
  EXPECT_EQ(t.last_command_id(), 7u);
  EXPECT_NEAR(t.cmd_v_m_s(), 0.2, 0.01);
}

namespace {
v1::Command trackLine(uint64_t id, double len, double v, const std::string& controller) {
  v1::Command c;
  c.set_id(id);
  c.mutable_track()->mutable_line()->set_length_m(len);
  c.mutable_track()->mutable_line()->set_speed_m_s(v);
  c.mutable_track()->set_controller(controller);
  return c;
}
}  // namespace

TEST(RobotCore, TrackingStopsForAnythingCloseAheadAndGoesOnWhenItClears) {
  Harness h;
  h.run(0.05);
  ASSERT_EQ(h.core.onCommand(trackLine(3, 3.0, 0.3, "direct"), h.t).status(), v1::Ack::ACCEPTED);
  h.run(1.0);
  EXPECT_GT(h.core.commandedTwist().v_m_s, 0.2);
  h.f.ultrasonic_mm[serial::kFrontRight] = 300;  // a box 0.30 m ahead of the sensor
  h.run(1.0);
  EXPECT_LT(std::abs(h.core.commandedTwist().v_m_s), 0.02);
  EXPECT_EQ(h.core.mode(), v1::TRACKING) << "a stop on the path, not the end of the run";
  bool told = false;
  for (const auto& e : h.core.takeEvents()) told = told || e.text.find("obstacle 30 cm ahead") != std::string::npos;
  EXPECT_TRUE(told);
  h.f.ultrasonic_mm[serial::kFrontRight] = serial::kNoEcho;
  h.run(1.5);
  EXPECT_GT(h.core.commandedTwist().v_m_s, 0.2);
}

TEST(RobotCore, TrackingRunsAPathAndAcksCompletion) {
  Harness h;
  h.run(0.05);
  // "direct": this harness's ideal MCU has no lag, on which a PID with the paper's gains oscillates.
  const auto ack = h.core.onCommand(trackLine(1, 0.5, 0.5, "direct"), h.t);
  ASSERT_EQ(ack.status(), v1::Ack::ACCEPTED) << ack.reason();
  EXPECT_EQ(h.core.mode(), v1::TRACKING);
  std::vector<v1::Ack> acks;
  for (int i = 0; i < 300 && acks.empty(); ++i) {
    h.step();
    acks = h.core.takeAcks();
  }
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].command_id(), 1u);
  EXPECT_EQ(acks[0].status(), v1::Ack::COMPLETED);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  EXPECT_NEAR(h.core.pose().x_m, 0.5, 0.05);
  v1::Telemetry t;
  h.core.fillTelemetry(t, h.t);
  EXPECT_DOUBLE_EQ(t.track_progress(), 1.0);
  EXPECT_GT(t.track_max_position_error_m(), 0.0);
}

TEST(RobotCore, TrackingIsRefusedOrEndedSafely) {
  Harness h;
  h.run(0.05);
  EXPECT_EQ(h.core.onCommand(trackLine(1, 2, 0.5, "fuzzy_pid"), h.t).status(), v1::Ack::REJECTED)
      << "no fuzzy-PID scheduler loaded in this core";
  EXPECT_EQ(h.core.onCommand(trackLine(2, 2, 0.5, "bogus"), h.t).status(), v1::Ack::REJECTED);
  EXPECT_EQ(h.core.onCommand(trackLine(3, -1, 0.5, "pid"), h.t).status(), v1::Ack::REJECTED);
  EXPECT_EQ(h.core.onCommand(trackLine(4, 2, 5.0, "pid"), h.t).status(), v1::Ack::REJECTED) << "above max speed";
  // Teleop takes over from tracking; stop ends tracking; e-stop refuses it.
  ASSERT_EQ(h.core.onCommand(trackLine(5, 2, 0.5, "direct"), h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.2);
  h.core.onCommand(teleop(6, 0.1, 0), h.t);
  EXPECT_EQ(h.core.mode(), v1::TELEOP);
  ASSERT_EQ(h.core.onCommand(trackLine(7, 2, 0.5, "direct"), h.t).status(), v1::Ack::ACCEPTED);
  h.core.onCommand(simple(8, 's'), h.t);
  EXPECT_EQ(h.core.mode(), v1::IDLE);
  h.core.onCommand(simple(9, 'e'), h.t);
  EXPECT_EQ(h.core.onCommand(trackLine(10, 2, 0.5, "direct"), h.t).status(), v1::Ack::REJECTED);
}

TEST(RobotCore, LinkLossDuringTrackingLatchesFailsafe) {
  Harness h;
  h.run(0.05);
  ASSERT_EQ(h.core.onCommand(trackLine(1, 5, 0.5, "direct"), h.t).status(), v1::Ack::ACCEPTED);
  h.run(0.5);
  h.core.onLinkDown(h.t, "closed");
  EXPECT_EQ(h.core.mode(), v1::FAILSAFE);
  EXPECT_EQ(h.core.commandNow().left_mrad_s, 0);
}
