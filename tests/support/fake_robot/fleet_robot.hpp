#pragma once
// The fake robot, as a fleet: many of them on one io_context (the link load
// generator and the malformed-input test):
// the real protocol over mutual TLS (net::makeTlsContext + net::LinkStream,
// the same code robot_client uses, with the certificate made for its id),
// Hello with the gas channels and gains of config/robot.yaml, heartbeats,
// telemetry with the fields robot_client fills (RobotCore::fillTelemetry),
// an Ack for every Command. Asynchronous (Boost.Asio): many robots share an
// io_context and its thread(s); each robot runs on a strand of its own.
//
// Telemetry numbering: Envelope.seq counts every message of the connection,
// and Telemetry.serial.frames_ok carries the telemetry's own sequence number
// (1, 2, ...: on a real robot the MCU's 100 Hz sensor frames, one per
// telemetry tick at 100 Hz), so a recording can be checked for gaps. Envelope.
// send_time_us and Telemetry.robot_time_us are CLOCK_MONOTONIC in µs at the
// moment the message is serialised and queued for the socket.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <random>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include "inspect_robot/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/tls.hpp"

namespace inspect::test {

struct FleetRobotOptions {
  std::string id;
  std::string certs_dir;        // <dir>/ca.pem, <dir>/<id>.pem, <dir>/<id>.key
  uint16_t port = 0;            // 127.0.0.1:port
  double telemetry_hz = 100.0;  // while telemetry is on
  double heartbeat_period_s = 0.1;
  uint32_t seed = 1;            // telemetry noise and start phase
};

/// Counters; read from any thread.
struct FleetRobotStats {
  std::atomic<bool> accepted{false};
  std::atomic<bool> rejected{false};
  std::atomic<bool> closed{false};          // the link ended (server closed it, or an error)
  std::atomic<uint64_t> telemetry_sent{0};  // = the last telemetry sequence number
  std::atomic<uint64_t> heartbeats_sent{0};
  std::atomic<uint64_t> heartbeats_received{0};
  std::atomic<uint64_t> commands_received{0};
  std::atomic<uint64_t> acks_sent{0};
  std::atomic<uint64_t> alarm_transitions_sent{0};
  std::atomic<uint64_t> app_bytes_sent{0};   // delimited frames handed to TLS
  std::atomic<uint64_t> app_bytes_received{0};
  std::atomic<int64_t> max_heartbeat_gap_us{0};   // between server heartbeats, after the HelloReply
  std::atomic<int64_t> max_write_backlog{0};      // bytes waiting behind a write in flight (peak)
};

class FleetRobot : public std::enable_shared_from_this<FleetRobot> {
 public:
  using Clock = std::chrono::steady_clock;
  FleetRobot(boost::asio::io_context& ioc, FleetRobotOptions options);
  ~FleetRobot();
  FleetRobot(const FleetRobot&) = delete;
  FleetRobot& operator=(const FleetRobot&) = delete;

  /// Connects, TLS handshake, Hello; heartbeats start with the accepted HelloReply.
  /// Throws net::TlsError when the certificate files cannot be used.
  void start();
  /// Telemetry at options.telemetry_hz from now on (each robot at its own phase).
  void startTelemetry();
  /// No more telemetry; heartbeats go on.
  void stopTelemetry();
  /// Telemetry as fast as the link takes it (a write always in flight, 64
  /// messages per write) for `duration`, then back to the normal rate or none.
  void flood(std::chrono::milliseconds duration);
  /// Sends Event{INFO, text} (the console prints "[id] INFO: text" once the server
  /// has processed it, after everything this robot sent before: a drain marker).
  void sendEvent(const std::string& text);
  /// A gas alarm transition: Event ALARM_RAISED / ALARM_CLEARED of CH4 LOW
  /// (channel 0), raise and clear in turn, each raise a new alarm id (1, 2, ...),
  /// robot_time_us = this machine's CLOCK_MONOTONIC (as its telemetry's).
  void sendAlarmTransition();
  /// Closes the connection (TLS close_notify is not waited for).
  void close();

  const std::string& id() const { return options_.id; }
  const FleetRobotStats& stats() const { return stats_; }
  /// Why the link ended ("" while it is up).
  std::string closeReason() const;
  /// The local "127.0.0.1:port" of the connection (what the server logs), "" before connecting.
  std::string localAddress() const;
  /// Bytes of TCP payload (TLS records) this connection had acknowledged by the
  /// server and received from it (the kernel's TCP_INFO); zeros when not connected.
  struct TcpBytes {
    uint64_t sent_acked = 0, received = 0;
  };
  TcpBytes tcpBytes() const;
  /// Reset the heartbeat gap measure (e.g. after a warm-up).
  void resetHeartbeatGap() { reset_gap_ = true; }

 private:
  void onConnected(const boost::system::error_code& ec);
  void doRead();
  void onRead(const boost::system::error_code& ec, std::size_t n);
  void handle(const v1::Envelope& env);
  void armHeartbeat();
  void armTelemetry(uint64_t generation);
  void sendTelemetryNow();
  void fillTelemetry(v1::Telemetry& t, uint64_t now_us);
  void queue(v1::Envelope& env);
  void flushWrites();
  void fail(const std::string& why);

  FleetRobotOptions options_;
  boost::asio::strand<boost::asio::io_context::executor_type> strand_;
  std::shared_ptr<boost::asio::ssl::context> tls_;
  std::unique_ptr<net::LinkStream> stream_;
  boost::asio::steady_timer hb_timer_;
  boost::asio::steady_timer tlm_timer_;
  net::DelimitedDecoder decoder_;
  std::array<char, 16 * 1024> rx_buf_{};
  std::string pending_;   // frames waiting for the write in flight
  std::string inflight_;  // the write in flight
  bool writing_ = false;
  bool up_ = false;
  uint64_t tx_seq_ = 0;
  bool alarm_active_ = false;  // sendAlarmTransition: the next is a clear
  uint64_t alarm_id_ = 0;
  uint64_t tlm_generation_ = 0;
  bool telemetry_on_ = false;
  Clock::time_point flood_until_{};
  Clock::time_point last_hb_rx_{};
  std::atomic<bool> reset_gap_{false};
  std::atomic<int> fd_{-1};  // for tcpBytes() from other threads
  v1::Envelope tlm_env_;  // reused: no allocation per message once grown
  std::mt19937 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  double t_s_ = 0;        // simulated time of the motion model
  FleetRobotStats stats_;
  mutable std::mutex info_mu_;
  std::string close_reason_;
  std::string local_address_;
};

/// "load001" ... for index 1 ...
std::string robotId(const std::string& prefix, int index);

}  // namespace inspect::test
