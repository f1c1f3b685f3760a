#pragma once
// The WebSocket upgrade's checks (docs/foxglove.md, "Security"): is it an
// upgrade, is the browser's Origin allowed, is the token right, which
// subprotocol. Pure functions of the HTTP request and the server's rules, so
// each is tested without a socket (tests/pc_server/foxglove/test_ws_upgrade.cpp).
#include <string>
#include <string_view>
#include <vector>

#include <boost/beast/http/message.hpp>
#include <boost/beast/http/status.hpp>
#include <boost/beast/http/string_body.hpp>

namespace inspect::server::foxglove {

using UpgradeRequest = boost::beast::http::request<boost::beast::http::string_body>;

/// What the upgrade check says: accepted with a subprotocol, or refused with
/// the HTTP status and a text naming what was wrong.
struct UpgradeVerdict {
  boost::beast::http::status status = boost::beast::http::status::ok;
  std::string reason;       // "" = accepted
  std::string subprotocol;  // the one chosen (accepted only)
  bool accepted() const { return reason.empty(); }
};

/// The token of a request: "Authorization: Bearer ..." or `?token=...` in the target; "" = none.
std::string requestToken(const UpgradeRequest& req);

/// True when the two secrets are equal; constant time for equal lengths.
bool sameSecret(std::string_view a, std::string_view b);

/// Checks an upgrade request in this order: a WebSocket upgrade at all; the
/// Origin (when `allowed_origins` is not empty and the request has one: a
/// browser's); the token (when `token` is not empty); a subprotocol this
/// server speaks among those offered.
UpgradeVerdict vetUpgrade(const UpgradeRequest& req, std::string_view token,
                          const std::vector<std::string>& allowed_origins);

}  // namespace inspect::server::foxglove
