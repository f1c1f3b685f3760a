#include "robot_client/robot_app.hpp"

#include <chrono>

#include "shared/config/config_node.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::client {

namespace asio = boost::asio;
using std::chrono::steady_clock;

namespace {
steady_clock::duration secs(double s) {
  return std::chrono::duration_cast<steady_clock::duration>(std::chrono::duration<double>(s));
}
}  // namespace

RobotApp::RobotApp(asio::io_context& io, const ClientConfig& cfg, const config::RobotConfig& robot,
                   const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler,
                   const std::string& cmd_log_path)
    : io_(io), cfg_(cfg), core_(robot, cfg.safety, control, std::move(scheduler)),
      serial_(io, cfg.serial_device, cfg.baud, cfg.serial_reopen_period_s), link_(io, cfg), tick_timer_(io),
      telemetry_timer_(io), mcu_hb_timer_(io), t0_ns_(monoNowNs()) {
  if (!cmd_log_path.empty()) {
    cmd_log_ = std::fopen(cmd_log_path.c_str(), "w");
    if (!cmd_log_) throw config::ConfigError("--cmd-log: cannot write " + cmd_log_path);
    std::setvbuf(cmd_log_, nullptr, _IOLBF, 0);  // readers see every command at once
    std::fprintf(cmd_log_, "# seq,left_mrad_s,right_mrad_s,flags\n");
  }
}

RobotApp::~RobotApp() {
  if (cmd_log_) std::fclose(cmd_log_);
}

double RobotApp::now() const { return static_cast<double>(monoNowNs() - t0_ns_) * 1e-9; }

void RobotApp::start() {
  serial_.start([this](const serial::Message& m, uint8_t) { onSerialMessage(m); },
                [this](bool open, const std::string&) {
                  core_.onSerialState(open, now());
                  flushEvents();
                });
  link_.start({[this] {
                 core_.onLinkUp(now());
                 flushEvents();
               },
               [this](const std::string& why) {
                 core_.onLinkDown(now(), why);
                 // Stop at once rather than waiting for the next sensor frame.
                 sendWheels(core_.commandNow());
                 flushEvents();
               },
               [this](const v1::Envelope& env) { onServerMessage(env); }});
  tick10ms();
  sendTelemetry();
  mcuHeartbeat();
}

void RobotApp::stop() {
  tick_timer_.cancel();
  telemetry_timer_.cancel();
  mcu_hb_timer_.cancel();
  // Leave the motors commanded to zero before going.
  if (serial_.isOpen()) sendWheels(serial::WheelCommand{});
  link_.stop();
}

void RobotApp::sendWheels(const serial::WheelCommand& c) {
  if (!serial_.isOpen()) return;
  const uint8_t seq = serial_.send(c);
  if (cmd_log_) std::fprintf(cmd_log_, "%u,%d,%d,%u\n", seq, c.left_mrad_s, c.right_mrad_s, c.flags);
}

void RobotApp::onSerialMessage(const serial::Message& m) {
  if (const auto* f = std::get_if<serial::SensorFrame>(&m)) {
    sendWheels(core_.onSensorFrame(*f, now()));
    flushEvents();
  }
  // Messages meant for the MCU (echoes on a loop-back) are ignored.
}

void RobotApp::onServerMessage(const v1::Envelope& env) {
  switch (env.body_case()) {
    case v1::Envelope::kHeartbeat: core_.onLinkActivity(now()); break;
    case v1::Envelope::kCommand: {
      v1::Envelope reply;
      *reply.mutable_ack() = core_.onCommand(env.command(), now());
      link_.send(reply);
      // A stop takes effect now, not at the next sensor frame.
      if (core_.mode() != v1::TELEOP && serial_.isOpen()) sendWheels(core_.commandNow());
      break;
    }
    default: log::debug("link", "ignoring message type ", static_cast<int>(env.body_case()));
  }
  flushEvents();
}

void RobotApp::flushEvents() {
  for (auto& a : core_.takeAcks()) {
    v1::Envelope env;
    *env.mutable_ack() = a;
    link_.send(env);
  }
  for (auto& e : core_.takeEvents()) {
    log::info("core", v1::Event::Kind_Name(e.kind), ": ", e.text);
    v1::Envelope env;
    auto* ev = env.mutable_event();
    ev->set_kind(e.kind);
    ev->set_text(e.text);
    ev->set_robot_time_us(static_cast<uint64_t>(now() * 1e6));
    link_.send(env);
  }
}

void RobotApp::tick10ms() {
  if (auto c = core_.onTimer(now())) sendWheels(*c);
  flushEvents();
  tick_timer_.expires_after(std::chrono::milliseconds(10));
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick10ms();
  });
}

void RobotApp::sendTelemetry() {
  core_.setSerialCounters(serial_.rxCounters(), serial_.bytesTx(), serial_.framesTx());
  if (link_.isUp()) {
    core_.fillTelemetry(*telemetry_env_.mutable_telemetry(), now());
    link_.send(telemetry_env_);
  }
  telemetry_timer_.expires_after(secs(1.0 / cfg_.telemetry_hz));
  telemetry_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) sendTelemetry();
  });
}

void RobotApp::mcuHeartbeat() {
  if (serial_.isOpen()) serial_.send(serial::Heartbeat{static_cast<uint32_t>(now() * 1000.0)});
  mcu_hb_timer_.expires_after(secs(cfg_.mcu_heartbeat_period_s));
  mcu_hb_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) mcuHeartbeat();
  });
}

}  // namespace inspect::client
