#pragma once
// Mutual TLS for the robot <-> server link (Boost.Asio SSL over OpenSSL), and
// the stream both programs read and write: TLS by default, plaintext TCP only
// when a program was started with --plaintext (docs/security.md).
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/ssl/stream.hpp>
#include <boost/asio/write.hpp>

namespace inspect::net {

/// Where a program finds its certificates. Paths are files (PEM).
struct TlsFiles {
  std::string ca;    // the CA that signed the peer's certificate
  std::string cert;  // this program's certificate
  std::string key;   // its private key (never logged, never sent)
};

/// A certificate or key that cannot be used; what() names the file and why.
class TlsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One line about a certificate for the log: "CN=robot1, expires 2029-02-24 (824 days), SHA-256 AB:CD:..".
/// Nothing secret: the subject, the expiry and the fingerprint of the public certificate.
std::string describeCertificate(const std::string& pem_file);

/// Role of a context: the server requires a client certificate for TLS
/// Web Client Authentication; the client requires a server certificate for
/// TLS Web Server Authentication naming the host it connects to. kWebServer
/// presents the server's certificate and asks for none (wss:// for browsers and
/// Foxglove, which authenticate with a token instead; `files.ca` unused).
enum class TlsRole { kServer, kClient, kWebServer };

/// A TLS 1.2+ context that verifies the peer against `files.ca` and presents
/// `files.cert`/`files.key`. Throws TlsError naming the file (missing,
/// unreadable, not PEM, key does not match the certificate, expired).
std::shared_ptr<boost::asio::ssl::context> makeTlsContext(const TlsFiles& files, TlsRole role);

/// The common name of the peer's verified certificate ("" if none).
std::string peerCommonName(SSL* ssl);

/// A handshake error in words, with a hint for the usual mistakes (a plaintext
/// peer, an unknown CA, an expired certificate, a certificate for another role).
std::string describeHandshakeError(const boost::system::error_code& ec, SSL* ssl);

/// A connected TCP socket, with TLS on top unless the context is null.
class LinkStream {
 public:
  using Tcp = boost::asio::ip::tcp;
  LinkStream(Tcp::socket socket, const std::shared_ptr<boost::asio::ssl::context>& tls)
      : tls_(tls), stream_(std::move(socket), tls ? *tls : plainContext()) {}

  bool tls() const { return tls_ != nullptr; }
  Tcp::socket& socket() { return stream_.next_layer(); }
  SSL* ssl() { return stream_.native_handle(); }

  /// Client: verify that the server's certificate names `host` (RFC 2818 rules) and send it as SNI.
  void expectServerName(const std::string& host);

  /// TLS handshake; with plaintext the handler runs at once with no error.
  template <class Handler>
  void asyncHandshake(boost::asio::ssl::stream_base::handshake_type type, Handler&& h) {
    if (!tls_) {
      boost::asio::post(stream_.get_executor(), [h = std::forward<Handler>(h)]() mutable { h({}); });
      return;
    }
    stream_.async_handshake(type, std::forward<Handler>(h));
  }
  template <class Buffer, class Handler>
  void asyncReadSome(const Buffer& b, Handler&& h) {
    if (tls_) stream_.async_read_some(b, std::forward<Handler>(h));
    else socket().async_read_some(b, std::forward<Handler>(h));
  }
  template <class Buffer, class Handler>
  void asyncWrite(const Buffer& b, Handler&& h) {
    if (tls_) boost::asio::async_write(stream_, b, std::forward<Handler>(h));
    else boost::asio::async_write(socket(), b, std::forward<Handler>(h));
  }
  /// Shuts the socket down and closes it (no TLS close_notify: a dead peer must not stall us).
  void close();

 private:
  static boost::asio::ssl::context& plainContext();
  std::shared_ptr<boost::asio::ssl::context> tls_;
  boost::asio::ssl::stream<Tcp::socket> stream_;
};

/// The banner both programs print (and log) in plaintext mode.
inline constexpr const char* kPlaintextWarning =
    "WARNING: --plaintext: the robot link is NOT encrypted and NOT authenticated; anyone on the network can "
    "read the telemetry and drive the robots. Use it only on an isolated test bench.";

}  // namespace inspect::net
