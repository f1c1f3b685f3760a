// The WebSocket upgrade's checks (pc_server/foxglove/ws_upgrade.cpp), each on
// a request built here: no socket. test_ws_server.cpp checks the same refusals
// over a real connection.
#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>
#include <boost/beast/http/verb.hpp>

#include "pc_server/foxglove/ws_upgrade.hpp"

using namespace inspect::server::foxglove;
namespace http = boost::beast::http;

namespace {
/// A browser's or a client library's upgrade request.
UpgradeRequest upgrade(const std::string& target = "/", const std::string& protocols = "foxglove.websocket.v1") {
  UpgradeRequest req(http::verb::get, target, 11);
  req.set(http::field::host, "127.0.0.1");
  req.set(http::field::upgrade, "websocket");
  req.set(http::field::connection, "Upgrade");
  req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  req.set(http::field::sec_websocket_version, "13");
  if (!protocols.empty()) req.set(http::field::sec_websocket_protocol, protocols);
  return req;
}
const std::vector<std::string> kAnyOrigin;
}  // namespace

TEST(WsUpgrade, ATokenComesFromTheQueryOrTheBearerHeader) {
  EXPECT_EQ(requestToken(upgrade("/?token=abc")), "abc");
  EXPECT_EQ(requestToken(upgrade("/?x=1&token=abc&y=2")), "abc");
  EXPECT_EQ(requestToken(upgrade("/?tokens=abc")), "");
  EXPECT_EQ(requestToken(upgrade("/")), "");
  auto req = upgrade("/?token=fromquery");
  req.set(http::field::authorization, "Bearer fromheader");
  EXPECT_EQ(requestToken(req), "fromheader") << "the header wins";
  req.set(http::field::authorization, "Basic dXNlcjpwYXNz");
  EXPECT_EQ(requestToken(req), "fromquery") << "not a bearer token: the query's";
}

TEST(WsUpgrade, SecretsCompareWhole) {
  EXPECT_TRUE(sameSecret("s3cret", "s3cret"));
  EXPECT_FALSE(sameSecret("s3cret", "s3creT"));
  EXPECT_FALSE(sameSecret("s3cret", "s3cre"));
  EXPECT_FALSE(sameSecret("", "x"));
  EXPECT_TRUE(sameSecret("", ""));
}

TEST(WsUpgrade, AcceptsARightTokenAndChoosesTheSubprotocol) {
  const auto v = vetUpgrade(upgrade("/?token=t0k", "foo, foxglove.websocket.v1"), "t0k", kAnyOrigin);
  EXPECT_TRUE(v.accepted()) << v.reason;
  EXPECT_EQ(v.status, http::status::ok);
  EXPECT_EQ(v.subprotocol, "foxglove.websocket.v1");
  EXPECT_TRUE(vetUpgrade(upgrade("/"), "", kAnyOrigin).accepted()) << "no token asked";
}

TEST(WsUpgrade, RefusesNamingWhatWasWrong) {
  struct Case {
    UpgradeRequest req;
    std::string token;
    std::vector<std::string> origins;
    http::status status;
    std::string says;
  };
  UpgradeRequest plain(http::verb::get, "/", 11);
  auto bad_origin = upgrade("/?token=t");
  bad_origin.set(http::field::origin, "https://evil.example");
  const std::vector<Case> cases{
      {plain, "", {}, http::status::bad_request, "connect with a WebSocket client"},
      {bad_origin, "t", {"https://app.foxglove.dev"}, http::status::forbidden, "origin 'https://evil.example' is not allowed"},
      {upgrade("/"), "t", {}, http::status::unauthorized, "a token is needed"},
      {upgrade("/?token=x"), "t", {}, http::status::unauthorized, "wrong token"},
      {upgrade("/", "chat, superchat"), "", {}, http::status::bad_request, "no supported subprotocol"},
      {upgrade("/", ""), "", {}, http::status::bad_request, "no supported subprotocol"},
  };
  for (const auto& c : cases) {
    const auto v = vetUpgrade(c.req, c.token, c.origins);
    EXPECT_FALSE(v.accepted()) << c.says;
    EXPECT_EQ(v.status, c.status) << c.says;
    EXPECT_NE(v.reason.find(c.says), std::string::npos) << v.reason;
    EXPECT_TRUE(v.subprotocol.empty());
  }
}

TEST(WsUpgrade, TheOriginIsCheckedOnlyWhenABrowserSendsOne) {
  const std::vector<std::string> allowed{"https://app.foxglove.dev"};
  EXPECT_TRUE(vetUpgrade(upgrade("/"), "", allowed).accepted()) << "no Origin: not a browser";
  auto req = upgrade("/");
  req.set(http::field::origin, "https://app.foxglove.dev");
  EXPECT_TRUE(vetUpgrade(req, "", allowed).accepted());
  req.set(http::field::origin, "https://app.foxglove.dev.evil.example");
  EXPECT_FALSE(vetUpgrade(req, "", allowed).accepted()) << "the whole origin, not a prefix";
  EXPECT_TRUE(vetUpgrade(req, "", kAnyOrigin).accepted()) << "no allow-list: any origin";
}

TEST(WsUpgrade, TheOriginIsCheckedBeforeTheToken) {
  // A page from a foreign origin learns nothing about the token.
  auto req = upgrade("/?token=right");
  req.set(http::field::origin, "https://evil.example");
  const auto v = vetUpgrade(req, "right", {"https://app.foxglove.dev"});
  EXPECT_EQ(v.status, http::status::forbidden);
}
