#include "shared/net/tls.hpp"

#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <cstdio>
#include <ctime>
#include <fstream>

#include <boost/asio/ssl/host_name_verification.hpp>

namespace inspect::net {

namespace ssl = boost::asio::ssl;

namespace {

struct FileCloser {
  void operator()(FILE* f) const { std::fclose(f); }
};
struct X509Free {
  void operator()(X509* x) const { X509_free(x); }
};
using X509Ptr = std::unique_ptr<X509, X509Free>;

std::string opensslError() {
  const unsigned long e = ERR_get_error();
  ERR_clear_error();
  if (e == 0) return "unknown error";
  char buf[256];
  ERR_error_string_n(e, buf, sizeof buf);
  return buf;
}

X509Ptr readCertificate(const std::string& path, const char* what) {
  if (path.empty()) throw TlsError(std::string("no ") + what + " certificate file given");
  std::unique_ptr<FILE, FileCloser> f(std::fopen(path.c_str(), "r"));
  if (!f) throw TlsError(std::string(what) + " certificate '" + path + "': cannot open (" + std::strerror(errno) +
                         "); make one with scripts/make_certs.sh");
  X509Ptr x(PEM_read_X509(f.get(), nullptr, nullptr, nullptr));
  if (!x) throw TlsError(std::string(what) + " certificate '" + path + "': not a PEM certificate");
  return x;
}

std::string commonName(X509* x) {
  X509_NAME* name = X509_get_subject_name(x);
  const int idx = name ? X509_NAME_get_index_by_NID(name, NID_commonName, -1) : -1;
  if (idx < 0) return "";
  ASN1_STRING* s = X509_NAME_ENTRY_get_data(X509_NAME_get_entry(name, idx));
  unsigned char* utf8 = nullptr;
  const int n = ASN1_STRING_to_UTF8(&utf8, s);
  if (n < 0) return "";
  std::string out(reinterpret_cast<char*>(utf8), static_cast<std::size_t>(n));
  OPENSSL_free(utf8);
  return out;
}

// Whole days from now to the certificate's notAfter (negative: expired).
int daysLeft(X509* x) {
  int days = 0, secs = 0;
  if (!ASN1_TIME_diff(&days, &secs, nullptr, X509_get0_notAfter(x))) return 0;
  return days;
}

std::string notAfterText(X509* x) {
  struct tm t {};
  if (!ASN1_TIME_to_tm(X509_get0_notAfter(x), &t)) return "?";
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", &t);
  return buf;
}

std::string fingerprint(X509* x) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (!X509_digest(x, EVP_sha256(), md, &n)) return "?";
  std::string out;
  char hex[4];
  for (unsigned i = 0; i < n && i < 8; ++i) {  // the first 8 bytes are enough to tell certificates apart
    std::snprintf(hex, sizeof hex, i ? ":%02X" : "%02X", md[i]);
    out += hex;
  }
  return out;
}

}  // namespace

std::string describeCertificate(const std::string& pem_file) {
  const auto x = readCertificate(pem_file, "the");
  return "CN=" + commonName(x.get()) + ", expires " + notAfterText(x.get()) + " (" +
         std::to_string(daysLeft(x.get())) + " days), SHA-256 " + fingerprint(x.get()) + "..";
}

std::shared_ptr<ssl::context> makeTlsContext(const TlsFiles& files, TlsRole role) {
  const bool server = role != TlsRole::kClient;
  const bool verify_peer = role != TlsRole::kWebServer;
  auto ctx = std::make_shared<ssl::context>(server ? ssl::context::tls_server : ssl::context::tls_client);
  SSL_CTX* c = ctx->native_handle();
  SSL_CTX_set_min_proto_version(c, TLS1_2_VERSION);
  ctx->set_options(ssl::context::default_workarounds | ssl::context::no_compression | ssl::context::single_dh_use);

  // Our own certificate: readable, current, and matching its key.
  const auto own = readCertificate(files.cert, server ? "server" : "robot");
  if (daysLeft(own.get()) < 0 || X509_cmp_current_time(X509_get0_notAfter(own.get())) <= 0)
    throw TlsError("certificate '" + files.cert + "' expired on " + notAfterText(own.get()) +
                   "; make a new one with scripts/make_certs.sh");
  if (X509_cmp_current_time(X509_get0_notBefore(own.get())) >= 0)
    throw TlsError("certificate '" + files.cert + "' is not valid yet (is this machine's clock right?)");
  if (verify_peer) {
    readCertificate(files.ca, "CA");  // a clear message before OpenSSL's
    if (SSL_CTX_load_verify_locations(c, files.ca.c_str(), nullptr) != 1)
      throw TlsError("CA certificate '" + files.ca + "': " + opensslError());
  }
  if (SSL_CTX_use_certificate_chain_file(c, files.cert.c_str()) != 1)
    throw TlsError("certificate '" + files.cert + "': " + opensslError());
  if (files.key.empty()) throw TlsError("no private key file given");
  {
    std::unique_ptr<FILE, FileCloser> f(std::fopen(files.key.c_str(), "r"));
    if (!f) throw TlsError("private key '" + files.key + "': cannot open (" + std::strerror(errno) + ")");
    EVP_PKEY* k = PEM_read_PrivateKey(f.get(), nullptr, nullptr, nullptr);
    ERR_clear_error();  // OpenSSL's text is not shown: nothing of a key reaches a log
    if (!k) throw TlsError("private key '" + files.key + "': not a PEM private key (or protected by a passphrase)");
    EVP_PKEY_free(k);
  }
  if (SSL_CTX_use_PrivateKey_file(c, files.key.c_str(), SSL_FILETYPE_PEM) != 1 || SSL_CTX_check_private_key(c) != 1)
    throw TlsError("private key '" + files.key + "' does not belong to certificate '" + files.cert + "'");
  ERR_clear_error();

  // The peer must present a certificate of the CA made for the other role:
  // a robot's certificate (client auth) cannot pose as the server and back.
  if (!verify_peer) {
    ctx->set_verify_mode(ssl::verify_none);
    return ctx;
  }
  ctx->set_verify_mode(ssl::verify_peer | ssl::verify_fail_if_no_peer_cert);
  SSL_CTX_set_purpose(c, server ? X509_PURPOSE_SSL_CLIENT : X509_PURPOSE_SSL_SERVER);
  return ctx;
}

std::string peerCommonName(SSL* s) {
  if (!s) return "";
  X509Ptr peer(SSL_get1_peer_certificate(s));
  if (!peer || SSL_get_verify_result(s) != X509_V_OK) return "";
  return commonName(peer.get());
}

std::string describeHandshakeError(const boost::system::error_code& ec, SSL* s) {
  std::string what = ec.message();
  if (s) {
    const long v = SSL_get_verify_result(s);
    if (v != X509_V_OK) what += " (" + std::string(X509_verify_cert_error_string(v)) + ")";
  }
  const auto has = [&](const char* needle) { return what.find(needle) != std::string::npos; };
  if (has("wrong version number") || has("http request") || has("unknown protocol") || has("packet length too long") ||
      has("unexpected message") || has("record layer failure"))
    what += " - the peer does not speak TLS: is it running with --plaintext?";
  else if (has("unable to get local issuer") || has("self-signed") || has("self signed") || has("unknown ca") ||
           has("unsupported certificate purpose") || has("unsuitable certificate purpose"))
    what += " - the peer's certificate is not one of this CA's for its role; make both with the same "
            "scripts/make_certs.sh directory";
  else if (has("certificate has expired") || has("certificate expired"))
    what += " - renew it with scripts/make_certs.sh";
  else if (has("peer did not return a certificate") || has("certificate required"))
    what += " - the robot presented no certificate";
  else if (has("unspecified certificate verification error"))
    what += " - the server's certificate does not name the host connected to: set tls.server_name, or remake "
            "server.pem with scripts/make_certs.sh --server-name <host>";
  else if (ec == boost::asio::error::eof || has("stream truncated"))
    what += " - the peer closed during the handshake (it may have refused our certificate)";
  return what;
}

void LinkStream::expectServerName(const std::string& host) {
  stream_.set_verify_callback(ssl::host_name_verification(host));
  // SNI only for names, not for IP addresses (RFC 6066).
  boost::system::error_code ec;
  boost::asio::ip::make_address(host, ec);
  if (ec) SSL_set_tlsext_host_name(stream_.native_handle(), host.c_str());
}

void LinkStream::close() {
  boost::system::error_code ignored;
  socket().shutdown(Tcp::socket::shutdown_both, ignored);
  socket().close(ignored);
}

ssl::context& LinkStream::plainContext() {
  static ssl::context ctx(ssl::context::tls);  // never used for a handshake
  return ctx;
}

}  // namespace inspect::net
