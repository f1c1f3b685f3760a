#pragma once
// One robot's TCP connection: handshake, delimited framing, heartbeats, the
// session timeout and the teleop set-point re-send. Every member is touched
// only on the session's strand; the public functions post to it.
#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <span>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <google/protobuf/arena.h>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/link/link_config.hpp"
#include "shared/util/token_bucket.hpp"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/tls.hpp"
#include "shared/util/log.hpp"

namespace inspect::server {

class LinkServer;
class RobotRegistry;

class RobotSession : public std::enable_shared_from_this<RobotSession> {
 public:
  using Strand = boost::asio::strand<boost::asio::io_context::executor_type>;
  using Clock = std::chrono::steady_clock;
  /// Unsent bytes allowed to pile up before the robot counts as not reading.
  static constexpr std::size_t kMaxQueuedBytes = 4u << 20;
  /// How long a rejected robot gets to read the HelloReply before the socket closes.
  static constexpr auto kRejectLinger = std::chrono::milliseconds(500);

  /// `socket` must use `strand` as its executor (accepted onto it); `tls`
  /// null = plaintext (--plaintext), else the TLS handshake comes first.
  RobotSession(Strand strand, boost::asio::ip::tcp::socket socket,
               const std::shared_ptr<boost::asio::ssl::context>& tls, LinkServer& server, RobotRegistry& registry,
               const LinkConfig& config, uint64_t serial);

  /// Starts the TLS handshake, then reading; arms the handshake timeout (TLS + Hello).
  void start();
  /// Closes the connection, logging `reason`; thread-safe.
  void close(std::string reason);
  /// Sends a command (id already set); Stop/EStop also clear the set-point. Thread-safe.
  void sendCommand(v1::Command cmd);
  /// Sends the set-point now with `first_id`, then re-sends it at teleop_resend_hz;
  /// with `lease_s` > 0, until it lapses unrenewed (then a zero set-point). Thread-safe.
  void setTeleop(double v_m_s, double w_rad_s, uint64_t first_id, double lease_s);
  /// Stops re-sending the set-point. Thread-safe.
  void clearTeleop();
  /// The operator is still there: a leased set-point's lease starts again
  /// from now (lease_s); nothing when no leased set-point is active. Thread-safe.
  void renewTeleop(double lease_s);

  uint64_t serial() const { return serial_; }
  /// Peer "ip:port" (fixed at construction).
  const std::string& address() const { return address_; }
  /// The common name of the robot's verified certificate ("" before the TLS handshake or in plaintext).
  const std::string& certificateName() const { return peer_.cert_name; }

 private:
  void doRead();
  void onRead(const boost::system::error_code& ec, std::size_t n);
  /// Returns false when the session was closed.
  bool handleFrame(std::span<const uint8_t> frame);
  void handleHello(const v1::Hello& hello);
  void acceptHello(const v1::Hello& hello);
  void rejectHello(const std::string& reason);
  void enqueue(v1::Envelope& env);
  void doWrite();
  void onWrite(const boost::system::error_code& ec);
  void armWatchdog();
  void armStaleCheck();
  void armHeartbeat();
  void armTeleop(uint64_t generation);
  void sendTeleopNow(uint64_t id);
  /// When the set-point's timer fires next: the re-send at `resend_at`, or its lapse if sooner.
  Clock::time_point nextTeleopAt(Clock::time_point resend_at) const;
  /// The lease ran out: a zero set-point goes out and the re-send stops.
  void lapseTeleop();
  void closeNow(const std::string& reason, log::Level level);
  /// The per-robot limits (robot_limits): false = drop this frame of `bytes`
  /// (throttled); closes a session that keeps on (then closed_).
  bool withinLimits(std::size_t bytes);
  /// A server event about this robot: on every console and in its run.
  void serverEvent(v1::Event::Kind kind, const std::string& text);
  std::string who() const;

  Strand strand_;
  net::LinkStream stream_;
  LinkServer& server_;
  RobotRegistry& registry_;
  const LinkConfig config_;
  const uint64_t serial_;
  std::string address_;

  boost::asio::steady_timer handshake_timer_;
  boost::asio::steady_timer watchdog_timer_;
  boost::asio::steady_timer heartbeat_timer_;
  boost::asio::steady_timer teleop_timer_;
  boost::asio::steady_timer stale_timer_;

  struct Throttle {
    util::TokenBucket messages, bytes;
    bool active = false;         // messages are being dropped
    double since_s = 0;          // the episode began (monotonic s)
    double last_drop_s = 0;
    uint64_t dropped = 0;        // in this episode
    uint64_t episodes = 0;
  } throttle_;

  net::DelimitedDecoder decoder_;
  /// Each received frame is parsed onto this arena and the arena reset once
  /// it is handled: a telemetry message's dozen sub-messages cost no malloc
  /// and free (docs/load.md). Its first block is kept across resets.
  static constexpr std::size_t kRxArenaBlock = 16 * 1024;
  std::unique_ptr<char[]> rx_arena_block_;
  std::unique_ptr<google::protobuf::Arena> rx_arena_;
  std::array<char, 16 * 1024> rx_buf_{};
  struct Outbox {
    std::deque<std::string> queue;
    std::size_t bytes = 0;  // queued, not yet written
    uint64_t seq = 0;       // Envelope.seq of the last message queued
  } tx_;

  struct Peer {
    std::string cert_name;      // CN of the robot's certificate, after the TLS handshake
    std::string robot_id;       // set by an accepted Hello
    bool accepted = false;
    bool rejecting = false;     // HelloReply{accepted=false} queued; close once sent
    std::string reject_reason;
    uint64_t event_stream = 0;  // Hello.event_stream: 0 = the robot stores and forwards nothing
    int64_t wall_offset_us = 0; // server UTC - robot UTC at the Hello (0 = unknown): files stored entries
    bool wall_known = false;
  } peer_;
  bool closed_ = false;
  /// A stored Event or Ack (store-and-forward): false when it was filed
  /// before (a resend: dropped). Sets `time_us` to when it happened (server
  /// clock) and confirms it to the robot.
  bool fileStored(const v1::Stored& s, uint64_t& time_us);

  struct Liveness {
    Clock::time_point last_rx;
    Clock::time_point last_telemetry;
    bool robot_moving = false;   // its last telemetry: a moving mode or a non-zero command
    bool stale_stopped = false;  // an EStop went out for the current telemetry gap
  } live_;

  struct Setpoint {  // the teleop set-point being re-sent
    bool active = false;
    double v_m_s = 0;
    double w_rad_s = 0;
    uint64_t generation = 0;  // bumps on every change, so stale timer chains end
    double lease_s = 0;       // > 0: lapses at lapse_at unless renewed
    Clock::time_point lapse_at{};
  } teleop_;
};

}  // namespace inspect::server
