// The operator service on its own: each call accepted, refused with the
// holder's name, completed, timed out, or invalid, on time passed in by the
// test (no terminal, no WebSocket, no real clock). The robot answers through
// the real registry when the test says so.
#include <gtest/gtest.h>

#include <filesystem>
#include <variant>

#include "pc_server/operator/operator_service.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "shared/util/clock.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::server;

namespace {

constexpr uint64_t kLinkSerial = 1;
constexpr int64_t kOneSecondNs = 1'000'000'000;

/// Records what would go to the robots; answers nothing by itself.
class RecordingSink : public CommandSink {
 public:
  uint64_t setTeleop(const std::string& robot, double v, double w, double lease_s) override {
    teleops.push_back({robot, v, w, lease_s});
    return ++next_id;
  }
  void clearTeleop(const std::string& robot) override { cleared.push_back(robot); }
  uint64_t sendCommand(const std::string& robot, v1::Command cmd) override {
    sent.emplace_back(robot, std::move(cmd));
    return ++next_id;
  }
  void consoleAlive() override {}

  struct Teleop {
    std::string robot;
    double v, w, lease_s;
  };
  std::vector<Teleop> teleops;
  std::vector<std::string> cleared;
  std::vector<std::pair<std::string, v1::Command>> sent;
  uint64_t next_id = 0;
};

class OperatorServiceTest : public ::testing::Test {
 protected:
  OperatorServiceTest() : service_(registry_, sink_, &control_, OperatorService::Options{}) {
    alice_ = control_.openSession("alice");
    bob_ = control_.openSession("bob");
    v1::Hello h;
    h.set_robot_id("robot1");
    registry_.onConnected("robot1", "127.0.0.1:1", kLinkSerial, h, now_);
  }

  /// The robot's Ack of the pending call, as the link would record it.
  void robotAnswers(const Issued& issued, v1::Ack::Status status, const std::string& reason = "") {
    const auto& p = std::get<PendingCall>(issued);
    v1::Ack a;
    a.set_command_id(p.command_id);
    a.set_status(status);
    a.set_reason(reason);
    registry_.onAck(p.robot, kLinkSerial, a);
  }
  // The Issued must outlive the references these return (keep it in a variable).
  static const PendingCall& pending(const Issued& issued) {
    EXPECT_TRUE(std::holds_alternative<PendingCall>(issued));
    return std::get<PendingCall>(issued);
  }
  static const CallResult& done(const Issued& issued) {
    EXPECT_TRUE(std::holds_alternative<CallResult>(issued));
    return std::get<CallResult>(issued);
  }

  int64_t now_ = 5 * kOneSecondNs;
  RobotRegistry registry_;
  RecordingSink sink_;
  ControlArbiter control_;
  OperatorService service_;
  uint64_t alice_ = 0, bob_ = 0;
};

TEST_F(OperatorServiceTest, StopIsAcceptedWhenTheRobotAcksItAndWaitsUntilThen) {
  const Issued issued = service_.stop(alice_, "robot1", now_);
  const PendingCall& p = pending(issued);
  ASSERT_EQ(sink_.sent.size(), 1u);
  EXPECT_TRUE(sink_.sent[0].second.has_stop());
  EXPECT_EQ(p.command_id, 1u);
  EXPECT_FALSE(service_.settle(p, now_ + kOneSecondNs / 2)) << "no Ack yet and the deadline is ahead";
  robotAnswers(issued, v1::Ack::ACCEPTED);
  const auto r = service_.settle(p, now_ + kOneSecondNs / 2);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, CallOutcome::kAccepted);
  EXPECT_TRUE(r->ok());
  EXPECT_EQ(r->text(), "robot1: stop accepted");
  EXPECT_FALSE(control_.holder("robot1")) << "a stop takes no control";
}

TEST_F(OperatorServiceTest, AMotionCallTakesAFreeRobotAndIsRefusedToAnotherSessionWithTheHoldersName) {
  const Issued first = service_.goTo(alice_, "robot1", 1.5, 2.0, 0.3, now_);
  EXPECT_EQ(pending(first).control_note, "robot1: control taken by alice (session 1)");
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].second.go_to();
  EXPECT_DOUBLE_EQ(g.points(0).x_m(), 1.5);
  EXPECT_DOUBLE_EQ(g.speed_m_s(), 0.3);

  const Issued second = service_.goTo(bob_, "robot1", 0, 0, std::nullopt, now_);
  const CallResult& refused = done(second);
  EXPECT_EQ(refused.outcome, CallOutcome::kRefused);
  EXPECT_NE(refused.reason.find("alice (session 1)"), std::string::npos) << refused.reason;
  EXPECT_EQ(refused.text().rfind("robot1: goto refused: ", 0), 0u) << refused.text();
  EXPECT_EQ(sink_.sent.size(), 1u) << "nothing sent for a refused call";
  // A stop and an e-stop are never refused: anyone may stop a robot.
  (void)pending(service_.stop(bob_, "robot1", now_));
  (void)pending(service_.estop(bob_, "robot1", now_));
  EXPECT_EQ(sink_.sent.size(), 3u);
}

TEST_F(OperatorServiceTest, ResumeCompletesWhenTheRobotSaysSo) {
  const Issued issued = service_.resume(alice_, "robot1", now_);
  robotAnswers(issued, v1::Ack::COMPLETED);
  const auto r = service_.settle(pending(issued), now_);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, CallOutcome::kCompleted);
  EXPECT_EQ(r->text(), "robot1: resume completed");
}

TEST_F(OperatorServiceTest, ACallTimesOutAtItsDeadlineAndNotBefore) {
  const Issued issued = service_.track(alice_, "robot1", TrackRequest{}, now_);
  const PendingCall& p = pending(issued);
  EXPECT_EQ(p.deadline_ns, now_ + kOneSecondNs) << "ack_timeout_s 1 s";
  EXPECT_FALSE(service_.settle(p, p.deadline_ns - 1));
  const auto r = service_.settle(p, p.deadline_ns);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, CallOutcome::kTimedOut);
  EXPECT_EQ(r->text(), "robot1: track: no ack within 1 s");
  // An Ack that comes late is still the answer of a later look.
  robotAnswers(issued, v1::Ack::ACCEPTED);
  EXPECT_EQ(service_.settle(p, p.deadline_ns + kOneSecondNs)->outcome, CallOutcome::kAccepted);
}

TEST_F(OperatorServiceTest, TheRobotsRejectionAndFailureCarryItsReason) {
  const Issued rejected = service_.ptz(alice_, "robot1", PtzRequest{false, 30, -10}, now_);
  robotAnswers(rejected, v1::Ack::REJECTED, "e-stop latched");
  EXPECT_EQ(service_.settle(pending(rejected), now_)->text(), "robot1: ptz rejected: e-stop latched");
  const Issued failed = service_.goTo(alice_, "robot1", 3, 0, std::nullopt, now_);
  robotAnswers(failed, v1::Ack::FAILED, "goal unreachable");
  const auto r = service_.settle(pending(failed), now_);
  EXPECT_EQ(r->outcome, CallOutcome::kRejected);
  EXPECT_EQ(r->text(), "robot1: goto failed: goal unreachable");
}

TEST_F(OperatorServiceTest, InvalidCallsNameWhatWasWrongAndSendNothing) {
  struct Case {
    Issued issued;
    std::string text;
  };
  VideoRequest res;
  res.what = VideoRequest::What::kRes;
  res.width = 7;
  res.height = 5;
  VideoRequest fps;
  fps.what = VideoRequest::What::kFps;
  TrackRequest laps;
  laps.laps = 0;
  TrackRequest line;
  line.shape = TrackRequest::Shape::kLine;
  line.size_m = 2000;
  const Case cases[] = {
      {service_.goTo(alice_, "robot1", 5000, 0, std::nullopt, now_), "goto: x and y must be in [-1000, 1000] m"},
      {service_.goTo(alice_, "robot1", 1, 1, 2.0, now_), "goto: speed 2 m/s is outside (0, 1]"},
      {service_.goTo(alice_, "", 1, 1, std::nullopt, now_), "goto: no robot selected"},
      {service_.goTo(alice_, "robot9", 1, 1, std::nullopt, now_), "goto: robot9 is not connected"},
      {service_.track(alice_, "robot1", laps, now_), "track: laps must be in (0, 100]"},
      {service_.track(alice_, "robot1", line, now_), "track: length must be in (0, 1000] m"},
      {service_.ptz(alice_, "robot1", PtzRequest{false, 200, 0}, now_),
       "ptz: pan must be within [-180, 180] and tilt within [-90, 90] degrees"},
      {service_.video(alice_, "robot1", res, now_), "video: res '7x5': want <W>x<H>, even, 64 to 4096 (e.g. 1280x720)"},
      {service_.video(alice_, "robot1", fps, now_), "video: fps '0': want 1 to 120"},
      {service_.teleop(alice_, "robot1", 5, 0, 0.3, now_), "drive: v 5 m/s is outside [-1, 1]"},
      {service_.teleop(alice_, "robot1", 0, std::nan(""), 0.3, now_), "drive: w nan rad/s is outside [-2, 2]"},
  };
  for (const auto& c : cases) {
    const CallResult& r = done(c.issued);
    EXPECT_EQ(r.outcome, CallOutcome::kInvalid) << c.text;
    EXPECT_EQ(r.text(), c.text);
  }
  EXPECT_TRUE(sink_.sent.empty());
  EXPECT_TRUE(sink_.teleops.empty());
  EXPECT_FALSE(control_.holder("robot1")) << "an invalid call takes no control";
}

TEST_F(OperatorServiceTest, TeleopGoesToTheSetPointWithItsLeaseAndVideoNeedsNoControl) {
  (void)pending(service_.teleop(alice_, "robot1", 0.4, -0.5, 0.3, now_));
  ASSERT_EQ(sink_.teleops.size(), 1u);
  EXPECT_DOUBLE_EQ(sink_.teleops[0].v, 0.4);
  EXPECT_DOUBLE_EQ(sink_.teleops[0].w, -0.5);
  EXPECT_DOUBLE_EQ(sink_.teleops[0].lease_s, 0.3);
  EXPECT_TRUE(sink_.sent.empty()) << "a set-point is not a one-off command";
  VideoRequest off;
  off.what = VideoRequest::What::kOff;
  const Issued video = service_.video(bob_, "robot1", off, now_);
  const PendingCall& p = pending(video);
  EXPECT_EQ(p.action, "video off");
  EXPECT_FALSE(sink_.sent.at(0).second.video().enabled());
  const Issued teleop = service_.teleop(bob_, "robot1", 0.1, 0, 0.3, now_);
  const CallResult& refused = done(teleop);
  EXPECT_EQ(refused.outcome, CallOutcome::kRefused);
}

TEST_F(OperatorServiceTest, AForcedTakeOverStopsTheRobotAndNamesThePreviousHolder) {
  EXPECT_EQ(service_.takeControl(alice_, "robot1", false, now_).text(),
            "robot1: control take completed (controlled by alice (session 1))");
  const CallResult polite = service_.takeControl(bob_, "robot1", false, now_);
  EXPECT_EQ(polite.outcome, CallOutcome::kInvalid);
  EXPECT_NE(polite.reason.find("alice (session 1)"), std::string::npos) << polite.reason;
  EXPECT_TRUE(sink_.sent.empty());
  const CallResult forced = service_.takeControl(bob_, "robot1", true, now_);
  EXPECT_TRUE(forced.ok());
  EXPECT_EQ(forced.reason, "control taken over from alice (session 1) (robot stopped)");
  ASSERT_EQ(sink_.sent.size(), 1u);
  EXPECT_TRUE(sink_.sent[0].second.has_stop());
  EXPECT_EQ(sink_.cleared, std::vector<std::string>{"robot1"});
  EXPECT_EQ(service_.releaseControl(alice_, "robot1").outcome, CallOutcome::kInvalid) << "alice holds it no more";
  EXPECT_TRUE(service_.releaseControl(bob_, "robot1").ok());
  EXPECT_FALSE(control_.holder("robot1"));
}

}  // namespace

TEST_F(OperatorServiceTest, ARouteSendsItsPointsNeedsControlAndDrawsItsMapOnceSent) {
  scene::SiteMaps maps;
  service_.setRunContext(nullptr, &maps);
  const Route r = loadRouteText("name: loop\nspeed_m_s: 0.3\nmap: " +
                                    inspect::test::srcPath("config/worlds/gas_lab.yaml") +
                                    "\nwaypoints_m: [1, 0, 1, 1, 0, 1]\n",
                                "loop.yaml");
  const Issued refused_first = service_.route(bob_, "", r, now_);
  EXPECT_EQ(done(refused_first).text(), "route: no robot selected");
  const Issued sent = service_.route(alice_, "robot1", r, now_);
  EXPECT_EQ(pending(sent).action, "route");
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].second.go_to();
  EXPECT_EQ(g.points_size(), 3);
  EXPECT_FALSE(g.inspection());
  EXPECT_DOUBLE_EQ(g.speed_m_s(), 0.3);
  EXPECT_NE(maps.get("robot1").version, 0u) << "the route's map is drawn for the robot";
  const Issued refused = service_.route(bob_, "robot1", r, now_);
  EXPECT_EQ(done(refused).outcome, CallOutcome::kRefused);
  EXPECT_EQ(maps.get("robot2").version, 0u);
  EXPECT_EQ(sink_.sent.size(), 1u);
}

TEST_F(OperatorServiceTest, InspectChecksItsSpeedAndSendsTheInspectionRound) {
  const Route r = loadRouteText("name: round\npoints:\n  - {at: [1, 0], dwell_s: 2}\n  - {at: [2, 0]}\n", "round.yaml");
  const Issued fast = service_.inspect(alice_, "robot1", r, 3.0, now_);
  EXPECT_EQ(done(fast).text(), "inspect: speed_m_s '3' must be a number in (0, 1] m/s");
  const Issued gone = service_.inspect(alice_, "robot9", r, std::nullopt, now_);
  EXPECT_EQ(done(gone).text(), "inspect: robot9 is not connected");
  const Route wheels = loadRouteText("name: wheels\nwheel_test: {standard: 2}\n", "wheels.yaml");
  const Issued not_round = service_.inspect(alice_, "robot1", wheels, std::nullopt, now_);
  EXPECT_EQ(done(not_round).text(), "inspect: 'wheels' is a wheel test, not an inspection route");
  EXPECT_TRUE(sink_.sent.empty());

  const Issued issued = service_.inspect(alice_, "robot1", r, 0.25, now_);
  ASSERT_EQ(sink_.sent.size(), 1u);
  const auto& g = sink_.sent[0].second.go_to();
  EXPECT_TRUE(g.inspection());
  EXPECT_DOUBLE_EQ(g.speed_m_s(), 0.25);
  EXPECT_DOUBLE_EQ(g.points(0).dwell_s(), 2);
  robotAnswers(issued, v1::Ack::ACCEPTED);
  const auto result = service_.settle(pending(issued), now_);
  ASSERT_TRUE(result);
  EXPECT_EQ(result->text(), "robot1: inspect accepted");
}

TEST_F(OperatorServiceTest, RecordStartAndStopCompleteAtOnceWithTheRunsId) {
  EXPECT_EQ(service_.recordStart(alice_, "robot1", "x").text(),
            "record: the server records nothing (recording.enabled: false or --no-record)");
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("inspect-opsvc-" + std::to_string(::getpid()) + "-" +
                                                    std::to_string(monoNowNs()));
  {
    RecordingConfig rc;
    rc.dir = dir.string();
    Recorder rec(rc, "test");
    service_.setRunContext(&rec, nullptr);
    EXPECT_EQ(service_.recordStart(alice_, "", "x").text(), "record: no robot selected");
    // Recording moves nothing: an observer may record a robot another session controls.
    (void)pending(service_.goTo(alice_, "robot1", 1, 1, std::nullopt, now_));
    const CallResult started = service_.recordStart(bob_, "robot1", "night round");
    ASSERT_EQ(started.outcome, CallOutcome::kCompleted) << started.text();
    const auto id = rec.activeRun("robot1");
    ASSERT_TRUE(id);
    EXPECT_EQ(started.reason, "recording run " + *id);
    EXPECT_EQ(rec.catalog().run(*id)->info.name, "night round");
    const CallResult again = service_.recordStart(alice_, "robot1", "");
    EXPECT_EQ(again.outcome, CallOutcome::kInvalid);
    EXPECT_NE(again.reason.find("already"), std::string::npos) << again.reason;
    const CallResult stopped = service_.recordStop(alice_, "robot1");
    EXPECT_EQ(stopped.outcome, CallOutcome::kCompleted);
    EXPECT_EQ(stopped.reason, "run " + *id + " stopped");
    EXPECT_EQ(service_.recordStop(alice_, "robot1").text(), "record: robot1 is not recording");
    service_.setRunContext(nullptr, nullptr);
  }
  fs::remove_all(dir);
}

TEST_F(OperatorServiceTest, AnySessionAcknowledgesAlarmsByNumberOrAll) {
  const auto raise = [&](uint64_t id, const std::string& ch) {
    v1::Event e;
    e.set_kind(v1::Event::ALARM_RAISED);
    auto* a = e.mutable_gas_alarm();
    a->set_id(id);
    a->set_channel_name(ch);
    a->set_level(v1::GasAlarm::HIGH);
    a->set_active(true);
    registry_.onEvent("robot1", kLinkSerial, e, now_);
  };
  EXPECT_EQ(service_.acknowledgeAlarms(bob_, std::nullopt, now_).error, "nothing to acknowledge");
  raise(1, "CH4");
  raise(2, "H2S");
  EXPECT_EQ(service_.acknowledgeAlarms(bob_, 9, now_).error, "no alarm #9 (alarms lists them)");
  const auto one = service_.acknowledgeAlarms(bob_, 2, now_);
  ASSERT_EQ(one.acked.size(), 1u);
  EXPECT_EQ(one.acked[0].first.robot_id, "robot1");
  EXPECT_EQ(one.acked[0].second, "alarm #2 (H2S HIGH) acknowledged by the operator");
  const auto rest = service_.acknowledgeAlarms(alice_, std::nullopt, now_);
  ASSERT_EQ(rest.acked.size(), 1u) << "#2 was acknowledged already";
  EXPECT_EQ(rest.acked[0].first.number, 1);
  EXPECT_TRUE(sink_.sent.empty()) << "acknowledging sends the robot nothing";
}

TEST_F(OperatorServiceTest, AGoalOutsideTheSiteMapIsRefusedWithItsBoundsUnlessForced) {
  scene::SiteMaps maps;
  maps.setDefault(inspect::test::srcPath("config/worlds/gas_lab.yaml"));  // walls 10 x 6 m, start (1.2, 1.5)
  service_.setRunContext(nullptr, &maps);
  const Issued outside = service_.goTo(alice_, "robot1", 9.0, 9.0, std::nullopt, now_);
  EXPECT_EQ(done(outside).outcome, CallOutcome::kInvalid);
  EXPECT_EQ(done(outside).reason,
            "(9, 9) is outside the site map gas_lab: its walls span x [-1.2, 8.8], y [-1.5, 4.5] m in the robot's "
            "odometry frame; `goto 9 9 force` sends it anyway");
  EXPECT_TRUE(sink_.sent.empty()) << "nothing sent";
  const Issued inside = service_.goTo(alice_, "robot1", 8.0, 4.0, std::nullopt, now_);
  EXPECT_EQ(pending(inside).action, "goto");
  const Issued forced = service_.goTo(alice_, "robot1", 9.0, 9.0, std::nullopt, now_, true);
  EXPECT_EQ(pending(forced).action, "goto");
  ASSERT_EQ(sink_.sent.size(), 2u);
  EXPECT_DOUBLE_EQ(sink_.sent[1].second.go_to().points(0).y_m(), 9.0);
  // No map for the robot: nothing to check against.
  service_.setRunContext(nullptr, nullptr);
  EXPECT_EQ(pending(service_.goTo(alice_, "robot1", 50.0, 50.0, std::nullopt, now_)).action, "goto");
}
