// The decision core's tick allocates nothing (shared/robot/robot_core.hpp):
// a counting operator new over this program (tests/support/alloc_counter), 10,000 ticks (100 s at 100 Hz)
// in every mode after a short warm-up, with people awareness on and echoes
// on the sonars. Commands (the command path, which may allocate) are sent
// between ticks and not counted.
#include <gtest/gtest.h>

#include "shared/behavior/human_awareness.hpp"
#include "shared/robot/awareness.hpp"
#include "tests/robot/core_commands.hpp"
#include "tests/robot/core_harness.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/paths.hpp"

namespace {

using namespace inspect;

constexpr int kTicks = 10000;

// A robot core with the real configs, people awareness on, and a harness
// that sends frames at 100 Hz with echoes: a wall 1.2 m to the left, and a
// front echo that comes and goes between 2.5 and 3.5 m.
struct AwareRobot {
  test::CoreHarness h;
  std::vector<robot::CoreEvent> events;
  uint64_t next_id = 1;

  AwareRobot() : h(config::loadControlConfigFile(test::srcPath("config/control.yaml"))) {
    auto acfg = behavior::loadAwarenessConfigFile(test::srcPath("config/behavior.yaml"));
    h.core.setAwareness(robot::makeAwareness(h.robot, acfg, {}, "config/behavior.yaml"));
    events.reserve(64);
  }

  /// One tick as robot_app runs it: heartbeat, frame, timer, the takes.
  void tick(int i) {
    h.f.ultrasonic_mm[2] = 1200;
    h.f.ultrasonic_mm[0] = static_cast<uint16_t>(3000 + 500 * ((i / 50) % 3 - 1));
    h.step();
    (void)h.core.onTimer(h.t + 0.005);
    h.core.takeEvents(events);
    (void)h.core.takeAcks();
    (void)h.core.takePtz();
  }

  /// `n` ticks with `between(i)` run before each (not counted); returns the
  /// allocations of the ticks alone.
  template <class Between>
  long count(int n, Between between) {
    long total = 0;
    for (int i = 0; i < n; ++i) {
      between(i);
      const std::size_t before = test::allocationCount();
      tick(i);
      total += static_cast<long>(test::allocationCount() - before);
    }
    return total;
  }
  long count(int n) {
    return count(n, [](int) {});
  }

  v1::Ack send(v1::Command c) {
    c.set_id(next_id++);
    return h.core.onCommand(c, h.t);
  }
};

v1::Command teleop(double v, double w) { return test::teleop(0, v, w); }

TEST(CoreAllocations, IdleTicksAllocateNothing) {
  AwareRobot r;
  r.count(200);
  EXPECT_EQ(r.h.core.mode(), v1::IDLE);
  EXPECT_EQ(r.count(kTicks), 0);
}

TEST(CoreAllocations, TeleopTicksAllocateNothing) {
  AwareRobot r;
  const auto resend = [&](int i) {
    if (i % 10 == 0) {
      ASSERT_EQ(r.send(teleop(0.2, 0.05)).status(), v1::Ack::ACCEPTED);
    }
  };
  r.count(200, resend);
  EXPECT_EQ(r.h.core.mode(), v1::TELEOP);
  EXPECT_EQ(r.count(kTicks, resend), 0);
  EXPECT_EQ(r.h.core.mode(), v1::TELEOP);
}

TEST(CoreAllocations, TrackingTicksAllocateNothing) {
  for (const char* controller : {"fuzzy_pid", "pid"}) {
    AwareRobot r;
    r.count(10);
    v1::Command c;
    c.mutable_track()->mutable_circle()->set_radius_m(3.5);
    c.mutable_track()->mutable_circle()->set_speed_m_s(0.3);
    c.mutable_track()->mutable_circle()->set_laps(10);
    c.mutable_track()->set_controller(controller);
    ASSERT_EQ(r.send(c).status(), v1::Ack::ACCEPTED) << controller;
    r.count(200);
    EXPECT_EQ(r.h.core.mode(), v1::TRACKING);
    EXPECT_EQ(r.count(kTicks), 0) << controller;
    EXPECT_EQ(r.h.core.mode(), v1::TRACKING) << controller;
  }
}

TEST(CoreAllocations, NavigatingTicksAllocateNothing) {
  AwareRobot r;
  r.count(10);
  v1::Command c;
  auto* p = c.mutable_go_to()->add_points();
  p->set_x_m(200.0);
  p->set_y_m(0.0);
  c.mutable_go_to()->set_speed_m_s(0.5);
  ASSERT_EQ(r.send(c).status(), v1::Ack::ACCEPTED);
  r.count(200);
  EXPECT_EQ(r.h.core.mode(), v1::NAVIGATING);
  EXPECT_EQ(r.count(kTicks), 0);
  EXPECT_EQ(r.h.core.mode(), v1::NAVIGATING);
}

TEST(CoreAllocations, WheelTestTicksAllocateNothing) {
  AwareRobot r;
  r.h.f.ultrasonic_mm.fill(serial::kNoEcho);
  r.count(10);
  v1::Command c;
  c.mutable_wheel_test()->set_name("alloc");
  auto* s = c.mutable_wheel_test()->add_segments();
  s->set_kind("chirp");
  s->set_duration_s(150.0);
  s->set_left_rad_s(1.0);
  s->set_right_rad_s(-1.0);
  s->set_f0_hz(0.2);
  s->set_f1_hz(2.0);
  ASSERT_EQ(r.send(c).status(), v1::Ack::ACCEPTED);
  r.count(200);
  EXPECT_EQ(r.h.core.mode(), v1::WHEEL_TEST);
  EXPECT_EQ(r.count(kTicks), 0);
  EXPECT_EQ(r.h.core.mode(), v1::WHEEL_TEST);
}

TEST(CoreAllocations, LatchedTicksAllocateNothing) {
  {
    AwareRobot r;
    r.count(10);
    v1::Command c;
    c.mutable_estop();
    ASSERT_EQ(r.send(c).status(), v1::Ack::ACCEPTED);
    r.count(200);
    EXPECT_EQ(r.h.core.mode(), v1::ESTOP);
    EXPECT_EQ(r.count(kTicks), 0);
  }
  {
    // FAILSAFE after the link went silent while driving, ticking on without heartbeats.
    AwareRobot r;
    ASSERT_EQ(r.send(teleop(0.2, 0.0)).status(), v1::Ack::ACCEPTED);
    for (int i = 0; i < 200; ++i) {
      r.h.step(false);
      (void)r.h.core.onTimer(r.h.t + 0.005);
      r.h.core.takeEvents(r.events);
    }
    ASSERT_EQ(r.h.core.mode(), v1::FAILSAFE);
    long total = 0;
    for (int i = 0; i < kTicks; ++i) {
      const std::size_t before = test::allocationCount();
      r.h.step(false);
      (void)r.h.core.onTimer(r.h.t + 0.005);
      r.h.core.takeEvents(r.events);
      total += static_cast<long>(test::allocationCount() - before);
    }
    EXPECT_EQ(total, 0);
  }
}

// The counter counts: a tick that raises an event allocates (its text), and
// the test sees it.
TEST(CoreAllocations, TheCounterSeesAnEventsAllocation) {
  AwareRobot r;
  r.count(10);
  const std::size_t before = test::allocationCount();
  r.h.core.onSerialState(false, r.h.t);  // FAULT_RAISED: a string
  EXPECT_GT(test::allocationCount(), before);
}

}  // namespace
