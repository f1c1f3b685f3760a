#pragma once
// The fake robot, scripted: one test drives it message by message (the server's
// link, TLS and console tests). On the fake robot's wire (tls_socket.hpp:
// blocking, TLS by OpenSSL directly) with the certificate of the robot id it
// says Hello with (tests/support/test_certs.hpp), the shared delimited framing
// and an optional background pump (heartbeats, telemetry, automatic Acks).
// Every wait is bounded in time.
#include <atomic>
#include <csignal>
#include <chrono>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/link_version.hpp"
#include "shared/net/robot_id.hpp"
#include "tests/support/fake_robot/robot_messages.hpp"
#include "tests/support/fake_robot/tls_socket.hpp"
#include "tests/support/test_certs.hpp"

namespace inspect::test {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

class ScriptedRobot {
 public:
  struct Received {
    Clock::time_point t;
    v1::Envelope env;
  };

  /// How the robot talks to the server: TLS with its own certificate (default),
  /// plaintext (a server started with --plaintext, or a robot that forgot TLS),
  /// or TLS with a certificate of another CA (`certs_dir`).
  enum class Mode { kTls, kPlaintext, kTlsNoCertificate };
  // OpenSSL writes with write(2): a server that closed must not kill the test with SIGPIPE.
  ScriptedRobot() { std::signal(SIGPIPE, SIG_IGN); }
  explicit ScriptedRobot(Mode mode, std::string certs_dir = "") : mode_(mode), certs_dir_(std::move(certs_dir)) {
    std::signal(SIGPIPE, SIG_IGN);
  }
  ~ScriptedRobot() {
    stopPump();
    close();
  }
  ScriptedRobot(const ScriptedRobot&) = delete;
  ScriptedRobot& operator=(const ScriptedRobot&) = delete;

  /// TCP connect; the TLS handshake follows with the first send (with the
  /// certificate of the Hello's robot id, else of `cert_id_` = "robot1").
  bool connect(uint16_t port) { return sock_.connect(port, 2.0); }

  /// The TLS handshake now, presenting the certificate made for `cert_id`; false
  /// (with tlsError()) if it failed. Called by the first send when not done yet.
  bool handshake(const std::string& cert_id) {
    std::lock_guard lk(tx_mu_);
    return handshakeLocked(cert_id);
  }
  const std::string& tlsError() const { return tls_error_; }
  /// The id whose certificate the first send presents when it is not a Hello with a valid id.
  std::string cert_id_ = "robot1";

  /// Half-close: the server reads EOF (no reset), the robot can still read.
  void shutdownWrite() { sock_.shutdownWrite(); }

  void close() {
    std::lock_guard lk(tx_mu_);
    sock_.close();
  }

  /// Bytes on the link (inside TLS unless plaintext), after the handshake.
  bool sendRaw(const std::string& bytes) { return sendRawAs(bytes, cert_id_); }

  bool send(v1::Envelope env) {
    env.set_seq(++tx_seq_);
    std::string wire;
    if (!net::appendDelimited(env, wire)) return false;
    const bool hello_id = env.has_hello() && net::validRobotId(env.hello().robot_id());
    return sendRawAs(wire, hello_id ? env.hello().robot_id() : cert_id_);
  }

  /// The next message from the server, or nullopt on timeout / close.
  std::optional<v1::Envelope> receive(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      std::span<const uint8_t> f;
      const auto st = decoder_.next(f);
      if (st == net::DelimitedDecoder::Status::kFrame) {
        v1::Envelope e;
        if (!net::DelimitedDecoder::parse(f, e)) return std::nullopt;
        return e;
      }
      if (st == net::DelimitedDecoder::Status::kInvalid) return std::nullopt;
      if (!readSome(deadline)) return std::nullopt;
    }
  }

  /// Sends Hello and returns the HelloReply (skipping nothing else: it must come first).
  std::optional<v1::HelloReply> hello(const std::string& id, uint32_t version = net::kProtocolVersion) {
    v1::Envelope e;
    *e.mutable_hello() = minimalHello(id, version);
    if (!send(e)) return std::nullopt;
    const auto r = receive(2000ms);
    if (!r || !r->has_hello_reply()) return std::nullopt;
    return r->hello_reply();
  }

  /// Reads and discards until the server closes the connection; false on timeout.
  bool waitClosed(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (!readSome(deadline)) return peer_closed_;
    }
    return peer_closed_;
  }

  /// Background thread: heartbeats every 100 ms, telemetry at `telemetry_hz` (0 = none)
  /// with pose.x = a counter, and an Ack for every Command (see ackPolicy).
  /// Telemetry pauses while set (heartbeats go on): the robot->server data goes stale.
  std::atomic<bool> mute_telemetry{false};
  void startPump(double telemetry_hz, bool heartbeats = true) {
    pumping_ = true;
    pump_ = std::thread([this, telemetry_hz, heartbeats] { pumpLoop(telemetry_hz, heartbeats); });
  }
  void stopPump() {
    pumping_ = false;
    if (pump_.joinable()) pump_.join();
  }

  /// Decides the Ack of a Command; default ACCEPTED. Set before startPump.
  std::function<v1::Ack(const v1::Command&)> ack_policy = acceptedAck;
  bool auto_ack = true;

  std::vector<Received> received() const {
    std::lock_guard lk(rx_mu_);
    return rx_;
  }
  int count(v1::Envelope::BodyCase c) const {
    std::lock_guard lk(rx_mu_);
    int n = 0;
    for (const auto& r : rx_) n += r.env.body_case() == c;
    return n;
  }
  bool peerClosed() const { return peer_closed_; }
  uint64_t telemetrySent() const { return telemetry_sent_; }

 private:
  bool sendRawAs(const std::string& bytes, const std::string& cert_id) {
    std::lock_guard lk(tx_mu_);
    if (sock_.fd() < 0 || !handshakeLocked(cert_id)) return false;
    return sock_.write(bytes);
  }

  bool handshakeLocked(const std::string& cert_id) {
    if (mode_ == Mode::kPlaintext || sock_.tls()) return true;
    if (sock_.fd() < 0 || !tls_error_.empty()) return false;
    const std::string dir = certs_dir_.empty() ? testCertsDir({cert_id}) : certs_dir_;
    const bool with_cert = mode_ == Mode::kTls;
    if (sock_.handshake(dir + "/ca.pem", with_cert ? dir + "/" + cert_id + ".pem" : "",
                        with_cert ? dir + "/" + cert_id + ".key" : ""))
      return true;
    tls_error_ = sock_.error();
    peer_closed_ = peer_closed_ || sock_.closed();
    return false;
  }

  bool readSome(Clock::time_point deadline) {
    if (sock_.fd() < 0 || peer_closed_) return false;
    if (mode_ != Mode::kPlaintext) {
      std::lock_guard lk(tx_mu_);
      if (!handshakeLocked(cert_id_)) return false;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    char buf[8192];
    std::unique_lock lk(tx_mu_);
    if (!sock_.pending()) {
      lk.unlock();  // a sender may write meanwhile
      if (!sock_.waitReadable(static_cast<int>(left))) return false;
      lk.lock();
    }
    std::size_t got = 0;
    const auto r = sock_.read(buf, sizeof buf, got);
    if (r == TlsSocket::Read::kClosed) {
      peer_closed_ = true;
      return false;
    }
    decoder_.append(buf, got);
    return true;
  }

  void pumpLoop(double telemetry_hz, bool heartbeats) {
    auto next_hb = Clock::now();
    auto next_tlm = Clock::now();
    const auto tlm_period = telemetry_hz > 0 ? std::chrono::duration_cast<Clock::duration>(
                                                   std::chrono::duration<double>(1.0 / telemetry_hz))
                                             : Clock::duration::max();
    while (pumping_ && !peer_closed_) {
      const auto now = Clock::now();
      if (heartbeats && now >= next_hb) {
        v1::Envelope e;
        e.mutable_heartbeat()->set_time_us(1);
        send(e);
        next_hb = now + 100ms;
      }
      if (telemetry_hz > 0 && now >= next_tlm && !mute_telemetry) {
        v1::Envelope e;
        auto* t = e.mutable_telemetry();
        t->mutable_pose()->set_x_m(static_cast<double>(++telemetry_sent_));
        t->set_mode(v1::TELEOP);
        t->set_battery_v(24.0);
        send(e);
        next_tlm += tlm_period;
        if (next_tlm < now) next_tlm = now + tlm_period;
      }
      if (auto m = receive(5ms)) {
        {
          std::lock_guard lk(rx_mu_);
          rx_.push_back({Clock::now(), *m});
        }
        if (auto_ack && m->has_command()) {
          v1::Envelope a;
          *a.mutable_ack() = ack_policy(m->command());
          send(a);
        }
      }
    }
  }

  Mode mode_ = Mode::kTls;
  std::string certs_dir_;
  TlsSocket sock_;
  std::string tls_error_;
  net::DelimitedDecoder decoder_;
  std::atomic<bool> peer_closed_{false};
  std::atomic<uint64_t> tx_seq_{0};
  std::atomic<uint64_t> telemetry_sent_{0};
  std::mutex tx_mu_;
  mutable std::mutex rx_mu_;
  std::vector<Received> rx_;
  std::atomic<bool> pumping_{false};
  std::thread pump_;
};

}  // namespace inspect::test
