#pragma once
// The Foxglove WebSocket server (Boost.Beast): accepts clients (ws:// or
// wss://, a token, an Origin allow-list), serves serverInfo / advertise /
// subscribe / unsubscribe / client publishing / service calls, and fans the
// messages published on its channels out to the subscribed clients, each
// through its own bounded SendQueue (a slow client never delays the robots,
// the console or another client). docs/foxglove.md. Thread-safe: publish()
// and the others may be called from any thread; handlers run on the io threads.
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/ssl/context.hpp>

#include "pc_server/foxglove/send_queue.hpp"
#include "pc_server/foxglove/ws_protocol.hpp"

namespace inspect::server::foxglove {

class ClientSession;

class WsServer {
 public:
  struct Options {
    std::string bind = "127.0.0.1";
    uint16_t port = 8765;                         // 0 = any free port (tests)
    std::string name = "pc_server";               // serverInfo.name
    std::string token;                            // "" = no token asked (loopback demos only)
    std::vector<std::string> allowed_origins;     // browsers' Origin header must be one of these; empty = any
    std::shared_ptr<boost::asio::ssl::context> tls;  // null = ws://
    std::size_t max_message_bytes = 64u << 10;    // longest client message; longer closes with "message too big"
    int max_clients = 32;
    double requests_per_s = 200;                  // client messages per second (burst: 2 s worth); more are refused
    SendQueue::Limits limits;
  };

  /// What the server's owner does with clients' publishing and service calls.
  /// Called on the client's strand (an io thread): must not block.
  struct Handler {
    virtual ~Handler() = default;
    virtual void onClientOpen(uint64_t client, const std::string& peer) = 0;
    virtual void onClientClose(uint64_t client) = 0;
    /// A client subscribed to `channel` (e.g. video: ask for a keyframe).
    virtual void onSubscribe(uint64_t client, uint32_t channel) = 0;
    /// A message on a channel the client advertised.
    virtual void onClientMessage(uint64_t client, const ClientChannel& channel, std::string_view payload) = 0;
    /// A service call; answer with respond() or failCall() (any thread, later is fine).
    virtual void onServiceCall(uint64_t client, const Service& service, uint32_t call_id, std::string_view payload) = 0;
  };

  /// What a channel's messages are, for the send queue's lanes.
  enum class Kind { kData, kVideo };

  WsServer(boost::asio::io_context& ioc, Options options, Handler& handler);
  ~WsServer();
  WsServer(const WsServer&) = delete;
  WsServer& operator=(const WsServer&) = delete;

  /// Binds and starts accepting. Throws util::StartupError naming the address.
  boost::asio::ip::tcp::endpoint listen();
  /// Closes every client (going away) and stops accepting; idempotent.
  void stop();

  /// Capabilities announced in serverInfo.
  static const std::vector<std::string>& capabilities();

  /// Adds a channel (its id is assigned) and advertises it to every client.
  uint32_t addChannel(Channel channel, Kind kind);
  /// Unadvertises a channel; its subscriptions end.
  void removeChannel(uint32_t id);
  /// Adds a service (id assigned); advertised to clients that connect afterwards and to those connected now.
  uint32_t addService(Service service);
  /// Sends `payload` (encoded as the channel says) to every subscriber of `channel`.
  /// `keyframe` matters for video channels only.
  void publish(uint32_t channel, uint64_t timestamp_ns, std::shared_ptr<const std::string> payload,
               bool keyframe = false);
  /// Whether anyone is subscribed to `channel` (skip building what nobody reads).
  bool subscribed(uint32_t channel) const;

  void respond(uint64_t client, uint32_t service_id, uint32_t call_id, std::string json);
  void failCall(uint64_t client, uint32_t service_id, uint32_t call_id, const std::string& message);
  /// A status message to one client (0 = every client).
  void status(uint64_t client, StatusLevel level, const std::string& message);

  struct ClientInfo {
    uint64_t id = 0;
    std::string peer;          // "ip:port"
    std::string subprotocol;
    double connected_s = 0;    // how long ago it connected
    std::vector<std::string> subscriptions;  // topics
    std::vector<std::string> publishing;     // topics it advertised
    std::size_t queued_bytes = 0, queued_messages = 0;
    SendQueue::Counters counters;
    uint64_t refused = 0;      // its messages refused (malformed, unknown, over the rate)
  };
  std::vector<ClientInfo> clients() const;
  /// Connections refused before the WebSocket upgrade (no or wrong token, bad Origin, no subprotocol).
  uint64_t refusedConnections() const { return refused_connections_.load(); }
  const Options& options() const { return options_; }

 private:
  // What the client sessions use (ClientSession is a friend; nothing else calls these).
  friend class ClientSession;
  struct ChannelEntry {
    Channel channel;
    Kind kind = Kind::kData;
  };
  std::vector<Channel> channelList() const;
  std::vector<Service> serviceList() const;
  bool findService(uint32_t id, Service& out) const;
  bool channelExists(uint32_t id, Kind* kind = nullptr) const;
  /// A session whose upgrade succeeded: greeted (serverInfo, advertise, services) and served from now on.
  void attach(const std::shared_ptr<ClientSession>& s);
  void detach(uint64_t client);
  Handler& handler() { return handler_; }
  std::string sessionId() const { return session_id_; }
  void noteRefused() { ++refused_connections_; }
  void handshakeEnded() { --handshaking_; }
  uint64_t nextClientId() { return next_client_.fetch_add(1); }

  void doAccept();
  std::shared_ptr<ClientSession> find(uint64_t client) const;

  boost::asio::io_context& ioc_;
  Options options_;
  Handler& handler_;
  std::string session_id_;
  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer accept_retry_;
  std::atomic<int> handshaking_{0};  // connections accepted, not yet served or refused
  std::atomic<uint64_t> next_client_{1};
  std::atomic<uint64_t> refused_connections_{0};
  mutable std::mutex mu_;
  bool stopped_ = false;
  uint32_t next_channel_ = 1;
  uint32_t next_service_ = 1;
  std::map<uint32_t, ChannelEntry> channels_;
  std::map<uint32_t, Service> services_;
  std::map<uint64_t, std::shared_ptr<ClientSession>> sessions_;
};

}  // namespace inspect::server::foxglove
