#pragma once
// One Foxglove client on the server's side (docs/foxglove.md): its
// subscriptions, the channels it advertises, its send queue and request rate,
// and the handling of each message it sends. The transport (plain or TLS,
// Beast's WebSocket) is the Session template of ws_server.cpp, derived from it.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pc_server/foxglove/send_queue.hpp"
#include "pc_server/foxglove/ws_protocol.hpp"
#include "pc_server/foxglove/ws_rate_limit.hpp"
#include "pc_server/foxglove/ws_server.hpp"

namespace inspect::server::foxglove {

class ClientSession : public std::enable_shared_from_this<ClientSession> {
 public:
  using Clock = std::chrono::steady_clock;
  ClientSession(WsServer& server, uint64_t id, std::string peer)
      : server_(server),
        id_(id),
        peer_(std::move(peer)),
        since_(Clock::now()),
        queue_(server.options().limits),
        rate_(server.options().requests_per_s) {}
  virtual ~ClientSession() { endHandshake(); }
  uint64_t id() const { return id_; }
  /// The connection is past its upgrade (served or refused): it no longer counts as setting up.
  void endHandshake();

  /// Queues a text message (control lane); closes the client when it is that far behind.
  void sendText(std::string json) { pushControl(OutMessage{std::move(json), nullptr, false}); }
  void sendBinaryControl(std::string bytes) { pushControl(OutMessage{std::move(bytes), nullptr, true}); }

  void deliver(uint32_t channel, WsServer::Kind kind, uint64_t ts, const std::shared_ptr<const std::string>& payload,
               bool keyframe);
  bool subscribedTo(uint32_t channel) const;
  /// The channel went away: its subscriptions end.
  void dropChannel(uint32_t channel);
  WsServer::ClientInfo info(const std::map<uint32_t, std::string>& topics) const;
  /// Closes the connection (going away); safe from any thread.
  virtual void close() = 0;
  /// Starts the TLS handshake (if any), the HTTP upgrade and then the session.
  virtual void start() = 0;

 protected:
  virtual void kick() = 0;  // writes the queue if no write is under way (on the strand)

  /// For the transports (ws_server.cpp): a connection refused before its
  /// upgrade, and a served client gone.
  void noteRefused() { server_.noteRefused(); }
  void detachFromServer() { server_.detach(id_); }

  void pushControl(OutMessage m);
  std::optional<OutMessage> nextOut();

  /// After the upgrade: the server sends serverInfo, the channels and the
  /// services as it attaches the session (no channel is advertised twice or
  /// before serverInfo), then the owner hears of the client.
  void greet();

  /// One status for the problems of one message (the first three, and how many more).
  void refuseAll(const std::string& op, const std::vector<std::string>& problems,
                 StatusLevel level = StatusLevel::kError);

  void refuse(const std::string& why, StatusLevel level = StatusLevel::kError);

  /// Whether this message is within the client's request rate (RequestRateLimit); tells it when not.
  bool withinRate();

  /// One message from the client (on the strand).
  void onMessage(bool text, std::string_view bytes);

  void handle(const Subscribe& s);
  void handle(const Unsubscribe& u);
  void handle(const ClientAdvertise& a);
  void handle(const ClientUnadvertise& u);
  void handle(const ClientMessageData& d);
  void handle(const ServiceCallRequest& r);
  void handle(const UnsupportedOp& u);

  WsServer& server_;
  const uint64_t id_;
  const std::string peer_;
  const Clock::time_point since_;
  std::string subprotocol_;
  mutable std::mutex mu_;
  SendQueue queue_;
  std::map<uint32_t, uint32_t> subs_;        // subscription id -> channel
  std::map<uint32_t, uint32_t> by_channel_;  // channel -> subscription id
  std::map<uint32_t, ClientChannel> client_channels_;
  uint64_t refused_ = 0;
  std::atomic<bool> handshaking_{true};
  uint64_t warned_drops_ = 0;
  Clock::time_point last_drop_warning_{};
  RequestRateLimit rate_;  // strand only
};

}  // namespace inspect::server::foxglove
