#pragma once
// A hostile or broken peer of pc_server's robot link for the malformed-input
// test: a blocking TCP socket to 127.0.0.1 with optional TLS on top (OpenSSL
// directly, with a certificate of the tests' CA: a stolen or buggy robot), that
// can write anything, inside or outside TLS. Every wait is bounded in time.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <openssl/err.h>
#include <openssl/ssl.h>

#include <chrono>
#include <optional>
#include <span>
#include <string>

#include "inspect/v1/link.pb.h"
#include "shared/net/delimited_codec.hpp"
#include "shared/net/link_version.hpp"

namespace inspect::linktest {

class AttackConn {
 public:
  using Clock = std::chrono::steady_clock;
  AttackConn() = default;
  ~AttackConn() { close(); }
  AttackConn(const AttackConn&) = delete;
  AttackConn& operator=(const AttackConn&) = delete;

  /// TCP connect (blocking, bounded by `timeout_s` for reads and writes afterwards).
  bool connect(uint16_t port, double timeout_s = 3.0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) return false;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return false;
    connected_at_ = Clock::now();
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    timeval tv{static_cast<time_t>(timeout_s), static_cast<suseconds_t>((timeout_s - static_cast<int>(timeout_s)) * 1e6)};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in l{};
    socklen_t len = sizeof l;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&l), &len);
    local_ = "127.0.0.1:" + std::to_string(ntohs(l.sin_port));
    return true;
  }

  /// TLS handshake with the certificate made for `id` in `certs_dir`; false with tlsError().
  bool handshake(const std::string& certs_dir, const std::string& id) {
    ctx_ = SSL_CTX_new(TLS_client_method());
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER, nullptr);
    const std::string ca = certs_dir + "/ca.pem", cert = certs_dir + "/" + id + ".pem",
                      key = certs_dir + "/" + id + ".key";
    if (SSL_CTX_load_verify_locations(ctx_, ca.c_str(), nullptr) != 1 ||
        SSL_CTX_use_certificate_chain_file(ctx_, cert.c_str()) != 1 ||
        SSL_CTX_use_PrivateKey_file(ctx_, key.c_str(), SSL_FILETYPE_PEM) != 1) {
      error_ = "cannot load " + cert;
      return false;
    }
    ssl_ = SSL_new(ctx_);
    SSL_set_fd(ssl_, fd_);
    if (SSL_connect(ssl_) != 1) {
      char buf[256];
      ERR_error_string_n(ERR_get_error(), buf, sizeof buf);
      error_ = std::string("TLS handshake failed: ") + buf;
      ERR_clear_error();
      return false;
    }
    return true;
  }

  /// Bytes straight onto the TCP socket (under TLS if there is one: corrupts its records).
  bool sendRaw(const std::string& bytes) {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const auto n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return false;
      off += static_cast<std::size_t>(n);
    }
    return true;
  }
  /// Bytes inside TLS.
  bool sendTls(const std::string& bytes) {
    if (!ssl_) return false;
    std::size_t off = 0;
    while (off < bytes.size()) {
      const int n = SSL_write(ssl_, bytes.data() + off, static_cast<int>(bytes.size() - off));
      if (n <= 0) {
        ERR_clear_error();
        return false;
      }
      off += static_cast<std::size_t>(n);
    }
    return true;
  }
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

  /// Reads and discards what the server sent so far (e.g. TLS session tickets), so that
  /// close() ends the connection with a FIN rather than a reset.
  void drainRaw() {
    char buf[4096];
    while (fd_ >= 0 && ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT) > 0) {
    }
  }
  /// TLS close_notify (a clean end of the TLS stream), then the TCP close.
  void closeNotify() {
    if (ssl_) SSL_shutdown(ssl_);
    close();
  }
  void close() {
    if (ssl_) SSL_free(ssl_);
    ssl_ = nullptr;
    if (ctx_) SSL_CTX_free(ctx_);
    ctx_ = nullptr;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  /// Reads and discards (raw bytes) until the server closes the connection;
  /// the time from connect() to the close, or nullopt when it stayed open for timeout_s.
  std::optional<double> waitClosedByServer(double timeout_s) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    char buf[4096];
    while (fd_ >= 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      const auto n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR))
        return std::chrono::duration<double>(Clock::now() - connected_at_).count();
    }
    return std::nullopt;
  }

  int fd() const { return fd_; }
  const std::string& local() const { return local_; }
  const std::string& tlsError() const { return error_; }
  Clock::time_point connectedAt() const { return connected_at_; }

 private:
  bool readTls(Clock::time_point deadline) {
    if (SSL_pending(ssl_) == 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return false;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left)) <= 0) return false;
    }
    char buf[4096];
    const int n = SSL_read(ssl_, buf, sizeof buf);
    if (n <= 0) {
      const int err = SSL_get_error(ssl_, n);
      ERR_clear_error();
      return err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE;
    }
    decoder_.append(buf, static_cast<std::size_t>(n));
    return true;
  }

  int fd_ = -1;
  SSL_CTX* ctx_ = nullptr;
  SSL* ssl_ = nullptr;
  std::string local_, error_;
  net::DelimitedDecoder decoder_;
  uint64_t seq_ = 0;
  Clock::time_point connected_at_{};
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
