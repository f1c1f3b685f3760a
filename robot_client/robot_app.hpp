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
  v1::Envelope telemetry_env_;  // reused to avoid reallocating repeated fields
  std::vector<robot::CoreEvent> events_;  // flushEvents' buffer, swapped with the core's
  // Sensor frame read -> its wheel command handed to the serial port
  // (logged at stop: the loop's figures of bench_loop, docs/deploy.md).
  util::LatencyHistogram frame_to_command_;
};

}  // namespace inspect::client
