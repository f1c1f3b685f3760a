// RobotCore's failsafes in the orders the fault injection found (docs/failsafes.md):
// a teleop set-point that expires in a silent link before the link timeout,
// and the handlers of a robot_client that was stopped (SIGSTOP) and goes on,
// where a late message or frame may be handled before the 10 ms timer.
#include <gtest/gtest.h>

#include <cmath>

#include "shared/robot/robot_core.hpp"
#include "tests/robot/core_commands.hpp"

using namespace inspect;
using robot::RobotCore;

namespace {

using test::teleop;

struct Robot {
  config::RobotConfig robot;
  // Link and command timeouts both 300 ms (the default link timeout is 250 ms,
  // which makes it fire first; equal timeouts are the race these tests cover),
  // sensor timeout 100 ms.
  robot::SafetyParams safety = [] {
    robot::SafetyParams s;
    s.link_timeout_s = 0.3;
    return s;
  }();
  RobotCore core{robot, safety};
  serial::SensorFrame f;
  double t = 0.0;
  serial::WheelCommand last;

  Robot() {
    f.ultrasonic_mm.fill(serial::kNoEcho);
    core.onSerialState(true, 0.0);
    core.onLinkUp(0.0);
  }
  void frame() {
    f.mcu_time_ms = static_cast<uint32_t>(std::lround(t * 1000));
    last = core.onSensorFrame(f, t);
  }
  // 100 Hz frames and timer ticks for `s` seconds; `every` > 0: a heartbeat every that many ticks.
  void run(double s, int teleop_every = 0, int heartbeat_every = 0) {
    const int n = static_cast<int>(std::lround(s / 0.01));
    for (int i = 0; i < n; ++i) {
      t += 0.01;
      if (teleop_every > 0 && i % teleop_every == 0) core.onCommand(teleop(100 + i, 0.0, 1.5), t);
      if (heartbeat_every > 0 && i % heartbeat_every == 0) core.onLinkActivity(t);
      frame();
      if (auto c = core.onTimer(t + 0.005)) last = *c;
    }
  }
  bool stopped() const { return last.left_mrad_s == 0 && last.right_mrad_s == 0; }
};

}  // namespace

// The last message before the silence was a heartbeat: the set-point expires
// (command_timeout_s) before the link times out (link_timeout_s). The link
// loss must still latch FAILSAFE and stop the wheels at once.
TEST(FailsafeCore, LinkSilenceAfterTheSetPointExpiredStillLatches) {
  Robot r;
  r.run(1.0, 5, 10);  // teleop at 20 Hz, heartbeats at 10 Hz
  ASSERT_EQ(r.core.mode(), v1::TELEOP);
  ASSERT_FALSE(r.stopped());
  r.t += 0.01;
  r.core.onCommand(teleop(1, 0.0, 1.5), r.t);  // the last teleop ...
  r.t += 0.03;
  r.core.onLinkActivity(r.t);  // ... and a heartbeat after it; then silence
  const double silent_from = r.t;
  r.run(0.29);  // the set-point is stale after 300 ms from the teleop: IDLE, ramping down
  r.run(0.05);  // the link is silent for 300 ms
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  EXPECT_TRUE(r.core.faults() & v1::FAULT_LINK_LOST);
  EXPECT_TRUE(r.stopped()) << "wheels at zero, not still ramping down";
  EXPECT_LT(r.t - silent_from, 0.35);
  // The console's re-sent set-point is refused when the link comes back.
  EXPECT_EQ(r.core.onCommand(teleop(2, 0.0, 1.5), r.t + 0.01).status(), v1::Ack::REJECTED);
}

// An operator's console that stops re-sending (heartbeats go on): the
// set-point expires and the robot stops; a later link loss is not a link
// loss while moving, and nothing is latched.
TEST(FailsafeCore, StaleSetPointWithALiveLinkDoesNotLatch) {
  Robot r;
  r.run(1.0, 5, 10);
  r.run(1.0, 0, 10);  // heartbeats only
  EXPECT_EQ(r.core.mode(), v1::IDLE);
  EXPECT_TRUE(r.core.faults() & v1::FAULT_COMMAND_STALE);
  r.run(0.5);  // now the link goes silent too
  EXPECT_TRUE(r.core.faults() & v1::FAULT_LINK_LOST);
  EXPECT_EQ(r.core.mode(), v1::IDLE);
}

// robot_client stopped (SIGSTOP) for a while, then continued: its handlers
// run in whatever order the ready events come, often before the 10 ms timer.
// Whichever comes first latches FAILSAFE, and nothing restarts after.
TEST(FailsafeCore, MessageFirstAfterAStallLatches) {
  Robot r;
  r.run(1.0, 5, 10);
  ASSERT_EQ(r.core.mode(), v1::TELEOP);
  r.t += 1.5;                                  // the process was stopped
  r.core.onLinkActivity(r.t);                  // a heartbeat is handled first ...
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  EXPECT_FALSE(r.core.faults() & v1::FAULT_LINK_LOST);  // ... and it ends the silence
  EXPECT_EQ(r.core.onCommand(teleop(1, 0.0, 1.5), r.t).status(), v1::Ack::REJECTED);
  r.frame();
  EXPECT_TRUE(r.stopped());
  r.run(0.5, 5, 10);  // frames and re-sent set-points flow again: no restart
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  EXPECT_TRUE(r.stopped());
}

TEST(FailsafeCore, FrameFirstAfterAStallLatches) {
  Robot r;
  r.run(1.0, 5, 10);
  r.t += 1.5;
  r.frame();  // an old frame of the backlog first
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  EXPECT_TRUE(r.stopped());
  EXPECT_EQ(r.core.onCommand(teleop(1, 0.0, 1.5), r.t).status(), v1::Ack::REJECTED);
}

TEST(FailsafeCore, CommandFirstAfterAStallIsRefused) {
  Robot r;
  r.run(1.0, 5, 10);
  r.t += 1.5;
  EXPECT_EQ(r.core.onCommand(teleop(1, 0.0, 1.5), r.t).status(), v1::Ack::REJECTED);
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
  r.frame();
  EXPECT_TRUE(r.stopped());
}

// A link loss found by the 10 ms timer returns the zero command at once,
// not at the next sensor frame.
TEST(FailsafeCore, TimerReturnsTheZeroCommandOfALatch) {
  Robot r;
  r.run(1.0, 5, 10);
  r.t += 0.01;
  r.core.onCommand(teleop(1, 0.0, 1.5), r.t);
  const double quiet = r.t;
  std::optional<serial::WheelCommand> c;
  for (int i = 1; i <= 1000 && !c; ++i) {
    r.t = quiet + 0.001 * i;
    if (i % 10 == 5) r.frame();
    else c = r.core.onTimer(r.t);
  }
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->left_mrad_s, 0);
  EXPECT_EQ(c->right_mrad_s, 0);
  EXPECT_EQ(c->flags, 0);
  EXPECT_NEAR(r.t - quiet, 0.3, 0.0021);
  EXPECT_EQ(r.core.mode(), v1::FAILSAFE);
}
