#pragma once
// A hostile or broken peer of pc_server's robot link for the malformed-input
// test, on the fake robot's wire (tests/support/fake_robot/tls_socket.hpp):
// TLS with a certificate of the tests' CA (a stolen or buggy robot), that can
// write anything, inside or outside TLS. Every wait is bounded in time.
#include <chrono>
#include <optional>
#include <span>
#include <string>

#include "inspect_robot/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/link_version.hpp"
#include "tests/support/fake_robot/tls_socket.hpp"

namespace inspect::linktest {

class AttackConn {
 public:
  using Clock = std::chrono::steady_clock;

  /// TCP connect (blocking, bounded by `timeout_s` for reads and writes afterwards).
  bool connect(uint16_t port, double timeout_s = 3.0) { return sock_.connect(port, timeout_s); }
  /// TLS handshake with the certificate made for `id` in `certs_dir`; false with tlsError().
  bool handshake(const std::string& certs_dir, const std::string& id) {
    return sock_.handshake(certs_dir + "/ca.pem", certs_dir + "/" + id + ".pem", certs_dir + "/" + id + ".key");
  }
  /// Bytes straight onto the TCP socket (under TLS if there is one: corrupts its records).
  bool sendRaw(const std::string& bytes) { return sock_.writeTcp(bytes); }
  /// Bytes inside TLS.
  bool sendTls(const std::string& bytes) { return sock_.tls() && sock_.write(bytes); }
  bool sendEnvelope(v1::Envelope env) {
    env.set_seq(++seq_);
    std::string wire;
    net::appendDelimited(env, wire);
    return sendTls(wire);
  }
  /// Hello for `id`; true when the server accepted it (HelloReply within 3 s).
  bool hello(const std::string& id) {
    v1::Envelope e;
    e.mutable_hello()->set_robot_id(id);
    e.mutable_hello()->set_protocol_version(net::kProtocolVersion);
    e.mutable_hello()->set_software_version("attacker");
    if (!sendEnvelope(e)) return false;
    const auto deadline = Clock::now() + std::chrono::seconds(3);
    while (Clock::now() < deadline) {
      std::span<const uint8_t> f;
      const auto st = decoder_.next(f);
      if (st == net::DelimitedDecoder::Status::kFrame) {
        v1::Envelope r;
        if (!net::DelimitedDecoder::parse(f, r)) return false;
        if (r.has_hello_reply()) return r.hello_reply().accepted();
        continue;
      }
      if (st == net::DelimitedDecoder::Status::kInvalid) return false;
      if (!readTls(deadline)) return false;
    }
    return false;
  }

  /// Reads and discards what the server sent so far, so that close() ends the
  /// connection with a FIN rather than a reset.
  void drainRaw() { sock_.drainTcp(); }
  /// TLS close_notify (a clean end of the TLS stream), then the TCP close.
  void closeNotify() { sock_.closeNotify(); }
  void close() { sock_.close(); }

  /// Reads and discards (raw bytes) until the server closes the connection;
  /// the time from connect() to the close, or nullopt when it stayed open for timeout_s.
  std::optional<double> waitClosedByServer(double timeout_s) {
    if (!sock_.waitClosedTcp(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s))))
      return std::nullopt;
    return std::chrono::duration<double>(Clock::now() - sock_.connectedAt()).count();
  }

  int fd() const { return sock_.fd(); }
  const std::string& local() const { return sock_.local(); }
  const std::string& tlsError() const { return sock_.error(); }
  Clock::time_point connectedAt() const { return sock_.connectedAt(); }

 private:
  bool readTls(Clock::time_point deadline) {
    if (!sock_.tls()) return false;
    if (!sock_.pending()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (!sock_.waitReadable(static_cast<int>(left))) return false;
    }
    char buf[4096];
    std::size_t got = 0;
    const auto r = sock_.read(buf, sizeof buf, got);
    if (r == test::TlsSocket::Read::kClosed) return false;
    decoder_.append(buf, got);
    return true;
  }

  test::TlsSocket sock_;
  net::DelimitedDecoder decoder_;
  uint64_t seq_ = 0;
};

/// A varint length prefix of `n`.
inline std::string varint(uint64_t n) {
  std::string s;
  while (n >= 0x80) {
    s.push_back(static_cast<char>((n & 0x7f) | 0x80));
    n >>= 7;
  }
  s.push_back(static_cast<char>(n));
  return s;
}

}  // namespace inspect::linktest
