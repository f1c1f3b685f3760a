// The Foxglove WebSocket server (pc_server/foxglove/ws_server) over real
// loopback sockets with a Beast client: the handshake (token, subprotocol),
// serverInfo and advertise, subscribe and message data with the client's
// subscription id, channels that come and go, and a client that never reads
// does not hold up the others.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "pc_server/foxglove/ws_server.hpp"
#include "shared/net/tls.hpp"
#include "tests/support/test_certs.hpp"

using namespace inspect::server::foxglove;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Json = nlohmann::json;

namespace {

struct NullHandler : WsServer::Handler {
  std::atomic<int> opened{0}, closed{0}, subscribed{0};
  void onClientOpen(uint64_t, const std::string&) override { ++opened; }
  void onClientClose(uint64_t) override { ++closed; }
  void onSubscribe(uint64_t, uint32_t) override { ++subscribed; }
  void onClientMessage(uint64_t, const ClientChannel&, std::string_view) override {}
  void onServiceCall(uint64_t, const Service&, uint32_t, std::string_view) override {}
};

struct Server {
  asio::io_context ioc;
  NullHandler handler;
  std::unique_ptr<WsServer> ws;
  std::thread thread;
  uint16_t port = 0;
  explicit Server(WsServer::Options o) {
    o.bind = "127.0.0.1";
    o.port = 0;
    ws = std::make_unique<WsServer>(ioc, o, handler);
    port = ws->listen().port();
    thread = std::thread([this] {
      auto guard = asio::make_work_guard(ioc);
      ioc.run();
    });
  }
  ~Server() {
    ws->stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ioc.stop();
    thread.join();
  }
};

/// A blocking client; every read has a deadline (the socket's receive timeout).
struct Client {
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws{ioc};
  std::string error;
  Client(uint16_t port, const std::string& target, const std::string& protocol = "foxglove.websocket.v1") {
    tcp::socket& s = ws.next_layer();
    s.connect({asio::ip::make_address("127.0.0.1"), port});
    const timeval tv{5, 0};
    ::setsockopt(s.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ws.set_option(websocket::stream_base::decorator(
        [protocol](websocket::request_type& r) { r.set(beast::http::field::sec_websocket_protocol, protocol); }));
    websocket::response_type res;
    beast::error_code ec;
    ws.handshake(res, "127.0.0.1", target, ec);
    if (ec) error = ec.message();
  }
  /// The next message: text as is, binary with a leading 'B'.
  std::string read() {
    beast::flat_buffer b;
    beast::error_code ec;
    ws.read(b, ec);
    if (ec) return "error: " + ec.message();
    return (ws.got_binary() ? "B" : "") + beast::buffers_to_string(b.data());
  }
  Json readJson() { return Json::parse(read(), nullptr, false); }
  void send(const std::string& text) {
    ws.text(true);
    ws.write(asio::buffer(text));
  }
};

/// The HTTP status a WebSocket upgrade request gets (raw HTTP, to see refusals).
int upgradeStatus(uint16_t port, const std::string& target, const std::string& protocol = "foxglove.websocket.v1") {
  asio::io_context ioc;
  tcp::socket s(ioc);
  s.connect({asio::ip::make_address("127.0.0.1"), port});
  const timeval tv{5, 0};
  ::setsockopt(s.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  beast::http::request<beast::http::empty_body> req{beast::http::verb::get, target, 11};
  req.set(beast::http::field::host, "127.0.0.1");
  req.set(beast::http::field::upgrade, "websocket");
  req.set(beast::http::field::connection, "upgrade");
  req.set(beast::http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  req.set(beast::http::field::sec_websocket_version, "13");
  req.set(beast::http::field::sec_websocket_protocol, protocol);
  beast::http::write(s, req);
  beast::flat_buffer b;
  beast::http::response<beast::http::string_body> res;
  beast::error_code ec;
  beast::http::read(s, b, res, ec);
  return ec ? -1 : static_cast<int>(res.result_int());
}

Channel channel(const std::string& topic) { return {0, topic, "protobuf", "foxglove.Log", "AAA=", "protobuf"}; }

}  // namespace

TEST(WsServer, RefusesWithoutTheTokenOrASubprotocol) {
  WsServer::Options o;
  o.token = "0123456789abcdef0123";
  Server s(o);
  EXPECT_EQ(upgradeStatus(s.port, "/"), 401);
  EXPECT_EQ(upgradeStatus(s.port, "/?token=wrong"), 401);
  EXPECT_EQ(upgradeStatus(s.port, "/?token=" + o.token, "other.v1"), 400);
  EXPECT_EQ(upgradeStatus(s.port, "/?token=" + o.token), 101);
  EXPECT_NE(Client(s.port, "/").error, "");
  Client ok(s.port, "/?token=" + o.token);
  EXPECT_EQ(ok.error, "");
  EXPECT_EQ(ok.readJson()["op"], "serverInfo");
  EXPECT_GE(s.ws->refusedConnections(), 3u);
}

TEST(WsServer, AdvertisesSubscribesAndSendsMessageData) {
  Server s(WsServer::Options{});
  const uint32_t a = s.ws->addChannel(channel("/a"), WsServer::Kind::kData);
  Client c(s.port, "/");
  ASSERT_EQ(c.error, "");
  const auto info = c.readJson();
  EXPECT_EQ(info["capabilities"], Json::array({"clientPublish", "services"}));
  const auto adv = c.readJson();
  ASSERT_EQ(adv["op"], "advertise");
  ASSERT_EQ(adv["channels"].size(), 1u);
  EXPECT_EQ(adv["channels"][0]["id"], a);
  c.send(R"({"op":"subscribe","subscriptions":[{"id":42,"channelId":)" + std::to_string(a) + "}]}");
  for (int i = 0; i < 100 && !s.ws->subscribed(a); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(s.ws->subscribed(a));
  s.ws->publish(a, 0x0102030405060708ULL, std::make_shared<const std::string>("hello"));
  const std::string m = c.read();
  ASSERT_EQ(m.size(), 1 + 13 + 5);
  EXPECT_EQ(m.substr(0, 6), std::string("B\x01\x2a\x00\x00\x00", 6));  // the client's subscription id, 42
  EXPECT_EQ(m.substr(6, 8), std::string("\x08\x07\x06\x05\x04\x03\x02\x01", 8));
  EXPECT_EQ(m.substr(14), "hello");
  // A channel that appears and goes is advertised and unadvertised.
  const uint32_t b = s.ws->addChannel(channel("/b"), WsServer::Kind::kData);
  EXPECT_EQ(c.readJson()["channels"][0]["topic"], "/b");
  s.ws->removeChannel(b);
  EXPECT_EQ(c.readJson()["channelIds"], Json::array({b}));
  // Reusing a subscription id is refused with a status naming it.
  c.send(R"({"op":"subscribe","subscriptions":[{"id":42,"channelId":)" + std::to_string(a) + "}]}");
  const auto st = c.readJson();
  EXPECT_EQ(st["op"], "status");
  EXPECT_EQ(st["level"], 2);
  EXPECT_EQ(st["message"], "subscription id 42 is already in use; subscription ignored");
}

TEST(WsServer, AClientThatNeverReadsDoesNotHoldUpTheOthers) {
  WsServer::Options o;
  o.limits.data_bytes = 4u << 20;
  Server s(o);
  const uint32_t a = s.ws->addChannel(channel("/a"), WsServer::Kind::kData);
  Client slow(s.port, "/"), good(s.port, "/");
  // Both subscribe; the slow one never reads again.
  for (Client* c : {&slow, &good}) {
    c->read();
    c->read();
    c->send(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":)" + std::to_string(a) + "}]}");
  }
  for (int i = 0; i < 100 && s.handler.subscribed < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(s.handler.subscribed, 2);
  const auto payload = std::make_shared<const std::string>(std::string(16 * 1024, 'x'));
  std::atomic<int> received{0};
  // 2000 messages of 16 KiB (32 MiB): far more than the slow client's socket
  // buffers and queue hold. The publisher stays at most 100 messages ahead of
  // the good client (so that it, however slow this machine, never overflows).
  std::thread reader([&] {
    for (int i = 0; i < 4000 && received < 2000; ++i) {
      const std::string m = good.read();
      if (m.rfind("error", 0) == 0) break;
      if (m.size() == 1 + 13 + payload->size()) ++received;  // (status texts are not data)
    }
  });
  double longest_publish_ms = 0;
  for (int i = 0; i < 2000; ++i) {
    for (int k = 0; k < 5000 && i - received > 100; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto t0 = std::chrono::steady_clock::now();
    s.ws->publish(a, static_cast<uint64_t>(i), payload);
    longest_publish_ms =
        std::max(longest_publish_ms, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  reader.join();
  EXPECT_EQ(received, 2000);  // the good client got everything
  // publish() queues and returns; it never waits for the slow client's socket (bounded, not a timing target).
  EXPECT_LT(longest_publish_ms, 1000.0);
  uint64_t slow_drops = 0;
  for (const auto& c : s.ws->clients()) slow_drops = std::max(slow_drops, c.counters.dropped_data);
  EXPECT_GT(slow_drops, 0u);  // the slow client's drops are counted
}

TEST(WsServer, ServesWssWithTheServersCertificateAndTheToken) {
  const std::string certs = inspect::test::testCertsDir();
  WsServer::Options o;
  o.token = "0123456789abcdef0123";
  o.tls = inspect::net::makeTlsContext({"", certs + "/server.pem", certs + "/server.key"},
                                       inspect::net::TlsRole::kWebServer);
  Server s(o);
  // A browser-like client: verifies the server against the CA, presents no certificate.
  asio::io_context ioc;
  asio::ssl::context ctx(asio::ssl::context::tls_client);
  ctx.load_verify_file(certs + "/ca.pem");
  ctx.set_verify_mode(asio::ssl::verify_peer);
  websocket::stream<beast::ssl_stream<tcp::socket>> ws(ioc, ctx);
  beast::get_lowest_layer(ws).connect({asio::ip::make_address("127.0.0.1"), s.port});
  const timeval tv{5, 0};
  ::setsockopt(beast::get_lowest_layer(ws).native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ws.next_layer().handshake(asio::ssl::stream_base::client);
  ws.set_option(websocket::stream_base::decorator(
      [](websocket::request_type& r) { r.set(beast::http::field::sec_websocket_protocol, "foxglove.sdk.v1"); }));
  ws.handshake("127.0.0.1", "/?token=" + o.token);
  beast::flat_buffer b;
  ws.read(b);
  const auto info = Json::parse(beast::buffers_to_string(b.data()), nullptr, false);
  EXPECT_EQ(info["op"], "serverInfo");
  // Plain WebSocket to the TLS port gets no upgrade.
  EXPECT_EQ(upgradeStatus(s.port, "/?token=" + o.token), -1);
}
