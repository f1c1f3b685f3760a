#pragma once
// The fake robot, scripted: one test drives it message by message (the server's
// link, TLS and console tests). A blocking POSIX socket with TLS on top
// (OpenSSL directly, with the certificate of the robot id it says Hello with,
// from tests/support/test_certs.hpp), the shared delimited framing and an optional
// background pump (heartbeats, telemetry, automatic Acks). Every wait is
// bounded in time.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <openssl/err.h>
#include <openssl/ssl.h>

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

#include "inspect/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/link_version.hpp"
#include "shared/net/robot_id.hpp"
#include "tests/support/fake_robot/robot_messages.hpp"
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
  bool connect(uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return false;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return false;
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    // Bounds every blocking read/write (the TLS handshake included).
    timeval tv{2, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    return true;
  }

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
  void shutdownWrite() { ::shutdown(fd_, SHUT_WR); }

  void close() {
    std::lock_guard lk(tx_mu_);
    if (ssl_) SSL_free(ssl_);
    ssl_ = nullptr;
    if (ctx_) SSL_CTX_free(ctx_);
    ctx_ = nullptr;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
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
    if (fd_ < 0 || !handshakeLocked(cert_id)) return false;
    std::size_t off = 0;
    while (off < bytes.size()) {
      if (ssl_) {
        const int n = SSL_write(ssl_, bytes.data() + off, static_cast<int>(bytes.size() - off));
        if (n <= 0) return false;
        off += static_cast<std::size_t>(n);
      } else {
        const auto n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
        if (n <= 0) return false;
        off += static_cast<std::size_t>(n);
      }
    }
    return true;
  }

  bool handshakeLocked(const std::string& cert_id) {
    if (mode_ == Mode::kPlaintext || ssl_) return true;
    if (fd_ < 0 || !tls_error_.empty()) return false;
    const std::string dir = certs_dir_.empty() ? testCertsDir({cert_id}) : certs_dir_;
    const std::string ca = dir + "/ca.pem", cert = dir + "/" + cert_id + ".pem", key = dir + "/" + cert_id + ".key";
    ctx_ = SSL_CTX_new(TLS_client_method());
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER, nullptr);
    if (SSL_CTX_load_verify_locations(ctx_, ca.c_str(), nullptr) != 1 ||
        (mode_ == Mode::kTls && (SSL_CTX_use_certificate_chain_file(ctx_, cert.c_str()) != 1 ||
                                 SSL_CTX_use_PrivateKey_file(ctx_, key.c_str(), SSL_FILETYPE_PEM) != 1))) {
      tls_error_ = "cannot load " + cert + " / " + key + " / " + ca;
      return false;
    }
    ssl_ = SSL_new(ctx_);
    SSL_set_fd(ssl_, fd_);
    if (SSL_connect(ssl_) != 1) {
      char buf[256];
      ERR_error_string_n(ERR_get_error(), buf, sizeof buf);
      tls_error_ = std::string("TLS handshake failed: ") + buf;
      ERR_clear_error();
      SSL_free(ssl_);
      ssl_ = nullptr;
      peer_closed_ = true;
      return false;
    }
    return true;
  }

  bool readSome(Clock::time_point deadline) {
    if (fd_ < 0 || peer_closed_) return false;
    if (mode_ != Mode::kPlaintext) {
      std::lock_guard lk(tx_mu_);
      if (!handshakeLocked(cert_id_)) return false;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    char buf[8192];
    if (ssl_) {
      std::unique_lock lk(tx_mu_);
      if (SSL_pending(ssl_) == 0) {
        lk.unlock();
        pollfd p{fd_, POLLIN, 0};
        if (::poll(&p, 1, static_cast<int>(left)) <= 0) return false;
        lk.lock();
      }
      if (!ssl_) return false;
      const int n = SSL_read(ssl_, buf, sizeof buf);
      if (n <= 0) {
        const int err = SSL_get_error(ssl_, n);
        ERR_clear_error();
        if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) return true;  // a TLS record without data
        peer_closed_ = true;
        return false;
      }
      decoder_.append(buf, static_cast<std::size_t>(n));
      return true;
    }
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left)) <= 0) return false;
    const auto n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) {
      peer_closed_ = true;
      return false;
    }
    decoder_.append(buf, static_cast<std::size_t>(n));
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
  SSL_CTX* ctx_ = nullptr;
  SSL* ssl_ = nullptr;
  std::string tls_error_;
  int fd_ = -1;
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
