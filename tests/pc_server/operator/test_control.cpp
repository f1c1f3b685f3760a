// One controlling operator per robot: two console sessions on one real
// LinkServer with a TLS test robot on 127.0.0.1.
#include <gtest/gtest.h>

#include <sstream>

#include "pc_server/console/console.hpp"
#include "tests/pc_server/server_fixture.hpp"

namespace inspect::test {
namespace {

using Body = v1::Envelope::BodyCase;

class ControlTest : public ServerFixture {
 protected:
  struct Session {
    std::ostringstream out;
    server::StopFlag stop;
    std::unique_ptr<server::Console> console;
    std::string take() {
      std::string s = out.str();
      out.str("");
      return s;
    }
  };

  void SetUp() override {
    startServer();
    ASSERT_TRUE(robot_.connect(port_));
    ASSERT_TRUE(robot_.hello("robot1"));
    robot_.startPump(20);
    ASSERT_TRUE(eventually([&] { return connected("robot1"); }));
    for (auto* s : {&alice_, &bob_}) {
      server::Console::Options o;
      o.ack_timeout_s = 2.0;
      s->console = std::make_unique<server::Console>(registry_, *link_, s->out, s->stop, o);
    }
    alice_.console->setSession(&control_, control_.openSession("alice"));
    bob_.console->setSession(&control_, control_.openSession("bob"));
    for (auto* s : {&alice_, &bob_}) {
      s->console->pump();  // selects robot1
      s->take();
    }
  }
  void TearDown() override {
    robot_.stopPump();
    ServerFixture::TearDown();
  }

  /// Teleop set-points the robot received with this v.
  int teleopsWithV(double v) const {
    int n = 0;
    for (const auto& r : robot_.received())
      n += r.env.has_command() && r.env.command().has_teleop() && r.env.command().teleop().v_m_s() == v;
    return n;
  }
  int received(v1::Command::KindCase k) const {
    int n = 0;
    for (const auto& r : robot_.received()) n += r.env.has_command() && r.env.command().kind_case() == k;
    return n;
  }

  ScriptedRobot robot_;
  server::ControlArbiter control_;
  Session alice_, bob_;
};

TEST_F(ControlTest, FirstMotionTakesAFreeRobotAndOthersAreRefusedWithAReason) {
  EXPECT_TRUE(alice_.console->execute("drive 0.2 0", 1));
  const auto a = alice_.take();
  EXPECT_NE(a.find("robot1: control taken by alice (session 1)"), std::string::npos) << a;
  EXPECT_NE(a.find("accepted"), std::string::npos) << a;

  for (const char* cmd : {"drive 0.1 0", "goto 1 1", "track circle 1", "resume", "ptz 10 0"}) {
    EXPECT_FALSE(bob_.console->execute(cmd, 1)) << cmd;
    const auto b = bob_.take();
    EXPECT_NE(b.find("refused: robot1 is controlled by alice (session 1)"), std::string::npos) << cmd << ": " << b;
  }
  // Nothing of bob's reached the robot.
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(teleopsWithV(0.1), 0);
  EXPECT_EQ(received(v1::Command::kGoTo), 0);
  EXPECT_EQ(received(v1::Command::kTrack), 0);
  EXPECT_EQ(received(v1::Command::kResume), 0);
  EXPECT_EQ(received(v1::Command::kPtz), 0);
  EXPECT_GT(teleopsWithV(0.2), 0);

  // An observer may always stop the robot.
  EXPECT_TRUE(bob_.console->execute("stop", 2));
  EXPECT_NE(bob_.take().find("robot1: stop accepted"), std::string::npos);
  EXPECT_TRUE(bob_.console->execute("estop", 3));
  EXPECT_GE(received(v1::Command::kEstop), 1);

  // control shows the holder to both.
  EXPECT_TRUE(bob_.console->execute("control", 4));
  const auto shown = bob_.take();
  EXPECT_NE(shown.find("this session: bob (session 2)"), std::string::npos) << shown;
  EXPECT_NE(shown.find("robot1: alice (session 1)"), std::string::npos) << shown;
  EXPECT_FALSE(bob_.console->execute("control take", 5));
  EXPECT_NE(bob_.take().find("control take force"), std::string::npos);
}

TEST_F(ControlTest, ObserversSeeEveryEvent) {
  v1::Envelope e;
  e.mutable_event()->set_kind(v1::Event::MODE_CHANGE);
  e.mutable_event()->set_text("mode TELEOP -> IDLE");
  ASSERT_TRUE(robot_.send(e));
  ASSERT_TRUE(eventually([&] { return !registry_.events("robot1").empty(); }));
  EXPECT_NE(alice_.console->background().find("mode TELEOP -> IDLE"), std::string::npos);
  EXPECT_NE(bob_.console->background().find("mode TELEOP -> IDLE"), std::string::npos);

  // A session that attaches later starts at the newest event: no replay of the buffer.
  Session carol;
  carol.console = std::make_unique<server::Console>(registry_, *link_, carol.out, carol.stop, server::Console::Options{});
  carol.console->setSession(&control_, control_.openSession("carol"));
  carol.console->eventsFromNow();
  EXPECT_EQ(carol.console->background().find("mode TELEOP -> IDLE"), std::string::npos);
  e.mutable_event()->set_text("mode IDLE -> TELEOP");
  ASSERT_TRUE(robot_.send(e));
  ASSERT_TRUE(eventually([&] {
    const auto ev = registry_.events("robot1");
    return !ev.empty() && ev.back().text() == "mode IDLE -> TELEOP";
  }));
  const auto late = carol.console->background();
  EXPECT_NE(late.find("mode IDLE -> TELEOP"), std::string::npos) << late;
  EXPECT_EQ(late.find("mode TELEOP -> IDLE"), std::string::npos) << late;
}

TEST_F(ControlTest, TakeForceStopsTheRobotAndTellsTheOldHolder) {
  ASSERT_TRUE(alice_.console->execute("drive 0.2 0", 1));
  alice_.take();
  const int stops0 = received(v1::Command::kStop);
  EXPECT_TRUE(bob_.console->execute("control take force", 1));
  EXPECT_NE(bob_.take().find("control taken over from alice (session 1) (robot stopped)"), std::string::npos);
  ASSERT_TRUE(eventually([&] { return received(v1::Command::kStop) > stops0; }));
  // The old holder's set-point is no longer re-sent.
  std::this_thread::sleep_for(200ms);
  const int resent = teleopsWithV(0.2);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(teleopsWithV(0.2), resent);
  EXPECT_NE(alice_.console->background().find("control of robot1 taken over by bob (session 2)"), std::string::npos);
  EXPECT_FALSE(alice_.console->execute("drive 0.3 0", 2));
  EXPECT_TRUE(bob_.console->execute("drive 0.1 0", 2));
}

TEST_F(ControlTest, AnAttachedSessionsDriveLapsesWhenItsOperatorFallsSilent) {
  // An attached console's session (pc_server/operator/operator_socket): its
  // drive lasts while lines or keep-alives keep coming, then lapses.
  Session carol;
  server::Console::Options o;
  o.ack_timeout_s = 2.0;
  o.drive_lease_s = 0.3;
  carol.console = std::make_unique<server::Console>(registry_, *link_, carol.out, carol.stop, o);
  carol.console->setSession(&control_, control_.openSession("carol"));
  carol.console->pump();
  carol.take();
  ASSERT_TRUE(carol.console->execute("drive 0.25 0", 1));
  EXPECT_NE(carol.take().find("accepted (re-sent while this session is active; it lapses 0.3 s after its last input)"),
            std::string::npos);
  auto last = std::chrono::steady_clock::now();
  for (int k = 0; k < 8; ++k) {  // the attach client's keep-alives, every 100 ms
    std::this_thread::sleep_for(100ms);
    carol.console->operatorPresent();
    last = std::chrono::steady_clock::now();
  }
  EXPECT_GE(teleopsWithV(0.25), 14) << "re-sent at 20 Hz while the operator was there";
  // Silent now: one zero set-point, 0.3 s after the last keep-alive.
  ASSERT_TRUE(eventually([&] { return teleopsWithV(0.0) > 0; }));
  std::chrono::steady_clock::time_point zero_at{};
  for (const auto& r : robot_.received())
    if (r.env.has_command() && r.env.command().has_teleop() && r.env.command().teleop().v_m_s() == 0.0) {
      zero_at = r.t;
      break;
    }
  const auto lapse_ms = std::chrono::duration_cast<std::chrono::milliseconds>(zero_at - last).count();
  RecordProperty("lapse_ms", static_cast<int>(lapse_ms));
  EXPECT_GE(lapse_ms, 250) << "not before the lease ran out";
  EXPECT_LT(lapse_ms, 600) << "the lease, not later (a loaded machine's room)";
  const int moving = teleopsWithV(0.25);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(teleopsWithV(0.25), moving) << "no re-send after the lapse";
  // A keep-alive after the lapse does not start it again; nor one after control passed on.
  carol.console->operatorPresent();
  ASSERT_TRUE(carol.console->execute("drive 0.25 0", 2));
  EXPECT_TRUE(bob_.console->execute("control take force", 1));
  ASSERT_TRUE(bob_.console->execute("drive 0.15 0", 2));
  for (int k = 0; k < 3; ++k) carol.console->operatorPresent();
  std::this_thread::sleep_for(500ms);
  const int after = teleopsWithV(0.25);
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(teleopsWithV(0.25), after) << "carol's set-point is gone with her control";
  EXPECT_GT(teleopsWithV(0.15), 0);
}

TEST_F(ControlTest, ReleaseAndLeavingFreeTheRobot) {
  ASSERT_TRUE(alice_.console->execute("drive 0.2 0", 1));
  EXPECT_TRUE(alice_.console->execute("control release", 2));
  EXPECT_NE(alice_.take().find("robot1: control released"), std::string::npos);
  EXPECT_FALSE(alice_.console->execute("control release", 3));  // not held any more
  EXPECT_TRUE(bob_.console->execute("drive 0.1 0", 1));
  EXPECT_NE(bob_.take().find("control taken by bob (session 2)"), std::string::npos);
  // A session that ends gives its robots free.
  EXPECT_EQ(control_.closeSession(bob_.console->session()), std::vector<std::string>{"robot1"});
  EXPECT_FALSE(control_.holder("robot1").has_value());
  EXPECT_TRUE(alice_.console->execute("drive 0.2 0", 4));
}

}  // namespace
}  // namespace inspect::test
