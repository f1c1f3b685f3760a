#pragma once
// robot_client's wiring: serial line + server link + control core on one
// io_context thread. The 100 Hz loop is driven by the MCU's sensor frames.
#include <cstdio>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include "robot_client/client_config.hpp"
#include "robot_client/event_outbox.hpp"
#include "robot_client/people_watcher.hpp"
#include "shared/robot/robot_core.hpp"
#include "robot_client/serial_link.hpp"
#include "robot_client/server_link.hpp"
#include "shared/config/control_config.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/util/latency_histogram.hpp"
#include "shared/util/token_bucket.hpp"
#include "shared/video/video_sender.hpp"

namespace inspect::client {

class RobotApp {
 public:
  RobotApp(boost::asio::io_context& io, const ClientConfig& cfg, const config::RobotConfig& robot,
           const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler,
           const std::string& cmd_log_path);
  ~RobotApp();
  void start();
  void stop();
  /// Logs the loop's figures so far (frame in -> command out) and starts
  /// them anew (SIGUSR1; stop() logs them too).
  void logLoopFigures();
  void setAwareness(std::unique_ptr<behavior::HumanAwareness> a) { core_.setAwareness(std::move(a)); }

 private:
  double now() const;
  void onSerialMessage(const serial::Message& m);
  void onServerMessage(const v1::Envelope& env);
  void sendWheels(const serial::WheelCommand& c);
  void flushEvents();
  /// Sends what the outbox has for this connection (a budget at a time).
  void pumpOutbox();
  void fillOutboxStatus(v1::Telemetry& t) const;
  void tick10ms();
  void sendTelemetry();
  void mcuHeartbeat();
  v1::Ack onVideoCommand(const v1::Command& cmd);
  v1::Ack onPtzCommand(const v1::Command& cmd);
  /// Sends a camera set-point to the MCU; "" or why not.
  std::string applyPtz(const v1::Ptz& p);
  void fillVideoStatus(v1::Telemetry& t) const;
  /// One head's stream figures (Telemetry.video, .wide_video).
  static void fillStream(const video::SenderStats& s, v1::VideoStatus& v);
  void fillPerception(v1::Telemetry& t) const;
  /// Turns the camera ahead while a tracked person is near and the robot
  /// moves, and gives the PTZ back look_ahead_hold_s after (perception.look_ahead).
  void lookAhead(double now_s);
  /// Active looking (config/behavior.yaml active_look): turns the PTZ head to
  /// a sonar track beside that no head has settled while nobody is ahead, and
  /// back ahead; only while the camera is left ahead and level (an operator's
  /// or a route's set-point is never taken over; either ends a look).
  void lookAside(double now_s);
  /// Ends a look aside without turning back (the operator or a route points the camera).
  void abandonLookAside(const char* why);
  /// Sends a set-point to the MCU and tells the people watcher; "" or why not.
  std::string sendPtz(const v1::Ptz& p);
  /// Gives the people tracker each head's newest detection (once each).
  void feedCamera();
  /// One head's newest detection to the tracker; `fed` the last one given.
  void feedHead(const PeopleWatcher& w, const config::CameraMount& mount, bool wide, uint64_t& fed);
  /// One head's detection figures and its fresh people into `p`.
  void fillHead(const PeopleWatcher& w, v1::Perception& p) const;
  /// Sets up the wide head (wide_head.source): its capture and its watcher.
  void openWideHead(const config::RobotConfig& robot);

  boost::asio::io_context& io_;
  ClientConfig cfg_;
  robot::RobotCore core_;
  SerialLink serial_;
  ServerLink link_;
  EventOutbox outbox_;
  util::TokenBucket outbox_budget_{800.0, 64.0};  // stored events sent per second
  boost::asio::steady_timer tick_timer_;
  boost::asio::steady_timer telemetry_timer_;
  boost::asio::steady_timer mcu_hb_timer_;
  int64_t t0_ns_;
  std::FILE* cmd_log_ = nullptr;
  std::unique_ptr<video::VideoSender> video_;  // null when the stream could not be set up
  double ptz_pan_rad_ = 0, ptz_tilt_rad_ = 0;
  std::unique_ptr<PeopleWatcher> watcher_;  // null: no detection (off, no video, a synthetic source)
  bool looking_ahead_ = false;       // the camera was turned ahead for people
  bool look_ahead_yielded_ = false;  // the operator moved the camera: not again until nobody is near
  double look_last_s_ = -1e9;        // last time people were near while moving
  v1::Ptz ptz_before_look_;          // the set-point to give back
  behavior::ActiveLookState aside_;  // active looking's planner state
  bool looking_aside_ = false;       // the PTZ head is turned (or turning) aside by it
  uint64_t aside_settled_us_ = 0;    // the PTZ head's pictures before this (monotonic us) were taken while it turned
  config::CameraMount camera_mount_;
  uint64_t camera_fed_seq_ = 0;      // the last detection given to the people tracker
  // The wide, fixed head (wide_head.source): captured without streaming, detected.
  std::unique_ptr<video::VideoSender> wide_video_;
  std::unique_ptr<PeopleWatcher> wide_watcher_;
  config::CameraMount wide_mount_;
  uint64_t wide_fed_seq_ = 0;
  v1::Envelope telemetry_env_;  // reused to avoid reallocating repeated fields
  std::vector<robot::CoreEvent> events_;  // flushEvents' buffer, swapped with the core's
  // Sensor frame read -> its wheel command handed to the serial port
  // (logged at stop: the loop's figures of bench_loop, docs/deploy.md).
  util::LatencyHistogram frame_to_command_;
};

}  // namespace inspect::client
