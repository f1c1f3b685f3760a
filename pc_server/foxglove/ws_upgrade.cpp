#include "pc_server/foxglove/ws_upgrade.hpp"

#include <openssl/crypto.h>

#include <boost/beast/websocket/rfc6455.hpp>

#include "pc_server/foxglove/ws_protocol.hpp"

namespace inspect::server::foxglove {

namespace http = boost::beast::http;

std::string requestToken(const UpgradeRequest& req) {
  const auto auth = req[http::field::authorization];
  if (auth.starts_with("Bearer ")) return std::string(auth.substr(7));
  const std::string_view target(req.target().data(), req.target().size());
  const auto q = target.find('?');
  if (q == std::string_view::npos) return "";
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view kv = query.substr(0, amp);
    if (kv.starts_with("token=")) return std::string(kv.substr(6));
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return "";
}

bool sameSecret(std::string_view a, std::string_view b) {
  return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

UpgradeVerdict vetUpgrade(const UpgradeRequest& req, std::string_view token,
                          const std::vector<std::string>& allowed_origins) {
  if (!boost::beast::websocket::is_upgrade(req))
    return {http::status::bad_request, "this is the Foxglove WebSocket bridge: connect with a WebSocket client", ""};
  if (!allowed_origins.empty()) {
    const auto origin = req[http::field::origin];
    if (!origin.empty()) {
      bool ok = false;
      for (const auto& a : allowed_origins) ok = ok || origin == a;
      if (!ok) return {http::status::forbidden, "origin '" + std::string(origin) + "' is not allowed", ""};
    }
  }
  if (!token.empty()) {
    const std::string t = requestToken(req);
    if (t.empty())
      return {http::status::unauthorized, "a token is needed: ws://host:port/?token=<token> (docs/foxglove.md)", ""};
    if (!sameSecret(t, token)) return {http::status::unauthorized, "wrong token", ""};
  }
  std::string offered;
  for (const auto& f : req)
    if (f.name() == http::field::sec_websocket_protocol) offered += std::string(f.value()) + ",";
  UpgradeVerdict v;
  v.subprotocol = chooseSubprotocol(offered);
  if (v.subprotocol.empty())
    return {http::status::bad_request, "no supported subprotocol offered (foxglove.websocket.v1 or foxglove.sdk.v1)", ""};
  return v;
}

}  // namespace inspect::server::foxglove
