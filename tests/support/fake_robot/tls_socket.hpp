#pragma once
// The fake robot's wire: a blocking TCP socket to 127.0.0.1 with optional TLS
// on top (OpenSSL directly, so that a test can also write under the TLS
// records or present no certificate at all). Used by the scripted robot and
// by the malformed-input test's hostile peer. Not thread-safe: the scripted
// robot locks around it. Every wait is bounded in time.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <openssl/err.h>
#include <openssl/ssl.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <string>

namespace inspect::test {

class TlsSocket {
 public:
  using Clock = std::chrono::steady_clock;
  /// What read() got.
  enum class Read { kData, kNothing, kClosed };

  TlsSocket() = default;
  ~TlsSocket() { close(); }
  TlsSocket(const TlsSocket&) = delete;
  TlsSocket& operator=(const TlsSocket&) = delete;

  /// TCP connect; every blocking read and write afterwards (the TLS handshake
  /// included) is bounded by `timeout_s`.
  bool connect(uint16_t port, double timeout_s) {
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
    const auto whole = static_cast<time_t>(timeout_s);
    timeval tv{whole, static_cast<suseconds_t>((timeout_s - static_cast<double>(whole)) * 1e6)};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in l{};
    socklen_t len = sizeof l;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&l), &len);
    local_ = "127.0.0.1:" + std::to_string(ntohs(l.sin_port));
    return true;
  }

  /// The TLS handshake, trusting `ca` and presenting `cert`/`key` (both empty:
  /// no client certificate). False with error(); `closed()` when the server
  /// ended the connection.
  bool handshake(const std::string& ca, const std::string& cert, const std::string& key) {
    if (fd_ < 0) return false;
    ctx_ = SSL_CTX_new(TLS_client_method());
    SSL_CTX_set_verify(ctx_, SSL_VERIFY_PEER, nullptr);
    if (SSL_CTX_load_verify_locations(ctx_, ca.c_str(), nullptr) != 1 ||
        (!cert.empty() && (SSL_CTX_use_certificate_chain_file(ctx_, cert.c_str()) != 1 ||
                           SSL_CTX_use_PrivateKey_file(ctx_, key.c_str(), SSL_FILETYPE_PEM) != 1))) {
      error_ = "cannot load " + cert + " / " + key + " / " + ca;
      ERR_clear_error();
      return false;
    }
    ssl_ = SSL_new(ctx_);
    SSL_set_fd(ssl_, fd_);
    if (SSL_connect(ssl_) != 1) {
      char buf[256];
      ERR_error_string_n(ERR_get_error(), buf, sizeof buf);
      error_ = std::string("TLS handshake failed: ") + buf;
      ERR_clear_error();
      SSL_free(ssl_);
      ssl_ = nullptr;
      closed_ = true;
      return false;
    }
    return true;
  }

  /// Bytes straight onto the TCP socket (under TLS if there is one: corrupts its records).
  bool writeTcp(const std::string& bytes) {
    std::size_t off = 0;
    while (off < bytes.size()) {
      const auto n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return false;
      off += static_cast<std::size_t>(n);
    }
    return true;
  }
  /// Bytes inside TLS, or on the TCP socket when there is no TLS.
  bool write(const std::string& bytes) {
    if (!ssl_) return writeTcp(bytes);
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

  /// True when read() can return data without waiting for the socket (TLS has some buffered).
  bool pending() const { return ssl_ && SSL_pending(ssl_) > 0; }
  /// Waits until the socket is readable, at most `timeout_ms`; false on timeout.
  bool waitReadable(int timeout_ms) const {
    if (fd_ < 0 || timeout_ms <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, timeout_ms) > 0;
  }
  /// One read (inside TLS if there is one) into buf; call after waitReadable()
  /// or pending(). kNothing: a TLS record without data, or nothing yet.
  Read read(char* buf, std::size_t size, std::size_t& got) {
    got = 0;
    if (fd_ < 0 || closed_) return Read::kClosed;
    if (ssl_) {
      const int n = SSL_read(ssl_, buf, static_cast<int>(size));
      if (n <= 0) {
        const int err = SSL_get_error(ssl_, n);
        ERR_clear_error();
        if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) return Read::kNothing;
        closed_ = true;
        return Read::kClosed;
      }
      got = static_cast<std::size_t>(n);
      return Read::kData;
    }
    const auto n = ::recv(fd_, buf, size, 0);
    if (n > 0) {
      got = static_cast<std::size_t>(n);
      return Read::kData;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return Read::kNothing;
    closed_ = true;
    return Read::kClosed;
  }

  /// Reads and discards, without TLS, what the server sent so far (e.g. TLS
  /// session tickets), so that close() ends the connection with a FIN rather than a reset.
  void drainTcp() {
    char buf[4096];
    while (fd_ >= 0 && ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT) > 0) {
    }
  }
  /// Reads and discards (raw bytes) until the server closes the connection;
  /// true when it did within `timeout`.
  bool waitClosedTcp(Clock::duration timeout) {
    const auto deadline = Clock::now() + timeout;
    char buf[4096];
    while (fd_ >= 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return false;
      if (!waitReadable(static_cast<int>(left))) continue;
      const auto n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) return closed_ = true;
    }
    return false;
  }

  /// Half-close: the server reads EOF (no reset), this side can still read.
  void shutdownWrite() { ::shutdown(fd_, SHUT_WR); }
  /// TLS close_notify (a clean end of the TLS stream), then close().
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

  bool tls() const { return ssl_ != nullptr; }
  bool closed() const { return closed_; }
  int fd() const { return fd_; }
  /// The local "127.0.0.1:port" (what the server logs).
  const std::string& local() const { return local_; }
  const std::string& error() const { return error_; }
  Clock::time_point connectedAt() const { return connected_at_; }

 private:
  int fd_ = -1;
  SSL_CTX* ctx_ = nullptr;
  SSL* ssl_ = nullptr;
  bool closed_ = false;
  std::string local_, error_;
  Clock::time_point connected_at_{};
};

}  // namespace inspect::test
