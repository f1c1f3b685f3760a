#include "pc_server/foxglove/ws_server.hpp"

#include <array>
#include <chrono>
#include <optional>

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>

#include "shared/util/startup_error.hpp"
#include "pc_server/foxglove/ws_client_session.hpp"
#include "pc_server/foxglove/ws_upgrade.hpp"
#include "shared/util/log.hpp"

namespace inspect::server::foxglove {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {
constexpr auto kUpgradeTimeout = std::chrono::seconds(10);
constexpr std::size_t kMaxHeaderBytes = 8192;
constexpr const char* kTag = "foxglove";

std::string endpointText(const tcp::endpoint& e) { return e.address().to_string() + ":" + std::to_string(e.port()); }

}  // namespace

template <class NextLayer>
class Session final : public ClientSession {
 public:
  template <class... Args>
  Session(WsServer& server, uint64_t id, std::string peer, Args&&... args)
      : ClientSession(server, id, std::move(peer)), ws_(std::forward<Args>(args)...) {}

  void start() override {
    if constexpr (kTls) {
      beast::get_lowest_layer(ws_).expires_after(kUpgradeTimeout);
      ws_.next_layer().async_handshake(asio::ssl::stream_base::server,
                                       [self = self()](beast::error_code ec) {
                                         if (ec) {
                                           log::info(kTag, "client ", self->peer_, ": TLS handshake failed: ", ec.message());
                                           self->noteRefused();
                                           self->endHandshake();
                                           return;
                                         }
                                         self->readRequest();
                                       });
    } else {
      readRequest();
    }
  }

  void close() override {
    asio::post(ws_.get_executor(), [self = self()] {
      if (self->closing_ || !self->open_) {
        beast::error_code ignored;
        beast::get_lowest_layer(self->ws_).socket().close(ignored);
        return;
      }
      self->closing_ = true;
      self->ws_.async_close(websocket::close_code::going_away, [self](beast::error_code) {});
    });
  }

 private:
  static constexpr bool kTls = !std::is_same_v<NextLayer, beast::tcp_stream>;
  std::shared_ptr<Session> self() { return std::static_pointer_cast<Session>(shared_from_this()); }

  void readRequest() {
    beast::get_lowest_layer(ws_).expires_after(kUpgradeTimeout);
    parser_.emplace();
    parser_->header_limit(kMaxHeaderBytes);
    parser_->body_limit(0);
    http::async_read(ws_.next_layer(), buffer_, *parser_, [self = self()](beast::error_code ec, std::size_t) {
      if (ec) {
        log::info(kTag, "client ", self->peer_, ": no WebSocket upgrade: ", ec.message());
        self->noteRefused();
        self->endHandshake();
        return;
      }
      self->onRequest(self->parser_->release());
    });
  }

  void onRequest(http::request<http::string_body> req) {
    const auto& o = server_.options();
    const UpgradeVerdict verdict = vetUpgrade(req, o.token, o.allowed_origins);
    if (!verdict.accepted()) {
      log::warn(kTag, "client ", peer_, " refused: ", verdict.reason);
      noteRefused();
      endHandshake();
      auto res = std::make_shared<http::response<http::string_body>>(verdict.status, req.version());
      res->set(http::field::content_type, "text/plain");
      res->set(http::field::connection, "close");
      res->body() = verdict.reason + "\n";
      res->prepare_payload();
      http::async_write(ws_.next_layer(), *res, [self = self(), res](beast::error_code, std::size_t) {
        beast::error_code ignored;
        beast::get_lowest_layer(self->ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
        beast::get_lowest_layer(self->ws_).socket().close(ignored);
      });
      return;
    }
    subprotocol_ = verdict.subprotocol;
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([p = subprotocol_](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, p);
      res.set(http::field::server, "inspect pc_server");
    }));
    ws_.read_message_max(server_.options().max_message_bytes);
    ws_.auto_fragment(false);
    ws_.async_accept(req, [self = self()](beast::error_code ec) {
      self->endHandshake();
      if (ec) {
        log::info(kTag, "client ", self->peer_, ": WebSocket accept failed: ", ec.message());
        return;
      }
      self->open_ = true;
      log::info(kTag, "client ", self->id_, " (", self->peer_, ") connected (", self->subprotocol_, ")");
      self->greet();
      self->doRead();
    });
  }

  void doRead() {
    ws_.async_read(in_, [self = self()](beast::error_code ec, std::size_t) {
      if (ec) {
        self->finish(ec);
        return;
      }
      const auto data = self->in_.cdata();
      const std::string_view bytes(static_cast<const char*>(data.data()), data.size());
      self->onMessage(self->ws_.got_text(), bytes);
      self->in_.consume(self->in_.size());
      self->doRead();
    });
  }

  void kick() override {
    asio::post(ws_.get_executor(), [self = self()] { self->doWrite(); });
  }
  void doWrite() {
    if (writing_ || !open_ || closing_) return;
    auto m = nextOut();
    if (!m) return;
    writing_ = true;
    out_ = std::move(*m);
    ws_.binary(out_.binary);
    const std::array<asio::const_buffer, 2> bufs{asio::buffer(out_.head),
                                                 out_.body ? asio::buffer(*out_.body) : asio::const_buffer()};
    ws_.async_write(bufs, [self = self()](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      self->out_ = {};
      if (ec) {
        self->finish(ec);
        return;
      }
      self->doWrite();
    });
  }

  void finish(const beast::error_code& ec) {
    if (finished_) return;
    finished_ = true;
    if (ec != websocket::error::closed && ec != asio::error::operation_aborted)
      log::info(kTag, "client ", id_, " (", peer_, ") gone: ", ec.message());
    else
      log::info(kTag, "client ", id_, " (", peer_, ") closed");
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
    if (open_) {
      open_ = false;
      detachFromServer();
    }
  }

  websocket::stream<NextLayer> ws_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  beast::flat_buffer in_;
  OutMessage out_;
  bool open_ = false, writing_ = false, closing_ = false, finished_ = false;
};

// ---------------------------------------------------------------------------

const std::vector<std::string>& WsServer::capabilities() {
  static const std::vector<std::string> caps{"clientPublish", "services"};
  return caps;
}

WsServer::WsServer(asio::io_context& ioc, Options options, Handler& handler)
    : ioc_(ioc), options_(std::move(options)), handler_(handler), acceptor_(asio::make_strand(ioc)),
      accept_retry_(acceptor_.get_executor()) {
  session_id_ = std::to_string(
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count());
}

WsServer::~WsServer() { stop(); }

tcp::endpoint WsServer::listen() {
  beast::error_code ec;
  const auto addr = asio::ip::make_address(options_.bind, ec);
  if (ec) throw util::StartupError("foxglove: bind address '" + options_.bind + "' is not a numeric IP address");
  const tcp::endpoint ep(addr, options_.port);
  const std::string where = options_.bind + ":" + std::to_string(options_.port);
  acceptor_.open(ep.protocol(), ec);
  if (!ec) acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(ep, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec)
    throw util::StartupError("foxglove: cannot listen on " + where + ": " + ec.message() +
                       (ec == asio::error::address_in_use ? " (another program uses the port; --foxglove-port or --no-foxglove)"
                                                          : ""));
  doAccept();
  const auto bound = acceptor_.local_endpoint();
  options_.port = bound.port();  // the report shows the port in use (0 asked for any)
  return bound;
}

void WsServer::doAccept() {
  acceptor_.async_accept(asio::make_strand(ioc_), [this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
      // Out of descriptors (EMFILE) and the like: try again in a moment, not in a busy loop.
      log::warn(kTag, "accept: ", ec.message(), "; retrying in 100 ms");
      accept_retry_.expires_after(std::chrono::milliseconds(100));
      accept_retry_.async_wait([this](const beast::error_code& e) {
        bool stopped;
        {
          std::lock_guard lk(mu_);
          stopped = stopped_;
        }
        if (!e && !stopped) doAccept();
      });
      return;
    } else {
      beast::error_code e2;
      const auto remote = socket.remote_endpoint(e2);
      const std::string peer = e2 ? std::string("?") : endpointText(remote);
      socket.set_option(tcp::no_delay(true), e2);
      bool full;
      {
        // Clients served and connections still setting up (not authenticated yet) count alike.
        std::lock_guard lk(mu_);
        full = stopped_ || static_cast<int>(sessions_.size()) + handshaking_.load() >= options_.max_clients;
      }
      if (full) {
        log::warn(kTag, "client ", peer, " refused: ", options_.max_clients, " clients connected or connecting already");
        noteRefused();
        socket.close(e2);
      } else {
        const uint64_t id = nextClientId();
        ++handshaking_;
        std::shared_ptr<ClientSession> s;
        if (options_.tls)
          s = std::make_shared<Session<beast::ssl_stream<beast::tcp_stream>>>(*this, id, peer, std::move(socket),
                                                                               *options_.tls);
        else
          s = std::make_shared<Session<beast::tcp_stream>>(*this, id, peer, std::move(socket));
        s->start();
      }
    }
    bool stopped;
    {
      std::lock_guard lk(mu_);
      stopped = stopped_;
    }
    if (!stopped) doAccept();
  });
}

void WsServer::stop() {
  std::map<uint64_t, std::shared_ptr<ClientSession>> sessions;
  {
    std::lock_guard lk(mu_);
    if (stopped_) return;
    stopped_ = true;
    sessions = sessions_;
  }
  asio::post(acceptor_.get_executor(), [this] {
    beast::error_code ignored;
    acceptor_.close(ignored);
    accept_retry_.cancel();
  });
  for (auto& [id, s] : sessions) s->close();
}

uint32_t WsServer::addChannel(Channel channel, Kind kind) {
  std::vector<std::shared_ptr<ClientSession>> all;
  {
    std::lock_guard lk(mu_);
    channel.id = next_channel_++;
    channels_[channel.id] = {channel, kind};
    for (auto& [id, s] : sessions_) all.push_back(s);
  }
  const std::string msg = advertiseJson({channel});
  for (auto& s : all) s->sendText(msg);
  return channel.id;
}

void WsServer::removeChannel(uint32_t id) {
  std::vector<std::shared_ptr<ClientSession>> all;
  {
    std::lock_guard lk(mu_);
    if (channels_.erase(id) == 0) return;
    for (auto& [cid, s] : sessions_) all.push_back(s);
  }
  const std::string msg = unadvertiseJson({id});
  for (auto& s : all) {
    s->dropChannel(id);
    s->sendText(msg);
  }
}

uint32_t WsServer::addService(Service service) {
  std::vector<std::shared_ptr<ClientSession>> all;
  {
    std::lock_guard lk(mu_);
    service.id = next_service_++;
    services_[service.id] = service;
    for (auto& [id, s] : sessions_) all.push_back(s);
  }
  const std::string msg = advertiseServicesJson({service});
  for (auto& s : all) s->sendText(msg);
  return service.id;
}

void WsServer::publish(uint32_t channel, uint64_t timestamp_ns, std::shared_ptr<const std::string> payload,
                       bool keyframe) {
  std::vector<std::shared_ptr<ClientSession>> subs;
  Kind kind;
  {
    std::lock_guard lk(mu_);
    const auto c = channels_.find(channel);
    if (c == channels_.end()) return;
    kind = c->second.kind;
    for (auto& [id, s] : sessions_)
      if (s->subscribedTo(channel)) subs.push_back(s);
  }
  for (auto& s : subs) s->deliver(channel, kind, timestamp_ns, payload, keyframe);
}

bool WsServer::subscribed(uint32_t channel) const {
  std::lock_guard lk(mu_);
  for (const auto& [id, s] : sessions_)
    if (s->subscribedTo(channel)) return true;
  return false;
}

void WsServer::respond(uint64_t client, uint32_t service_id, uint32_t call_id, std::string json) {
  if (auto s = find(client)) s->sendBinaryControl(serviceCallResponse(service_id, call_id, "json", json));
}

void WsServer::failCall(uint64_t client, uint32_t service_id, uint32_t call_id, const std::string& message) {
  if (auto s = find(client)) s->sendText(serviceCallFailureJson(service_id, call_id, message));
}

void WsServer::status(uint64_t client, StatusLevel level, const std::string& message) {
  std::vector<std::shared_ptr<ClientSession>> to;
  {
    std::lock_guard lk(mu_);
    for (auto& [id, s] : sessions_)
      if (client == 0 || id == client) to.push_back(s);
  }
  const std::string msg = statusJson(level, message);
  for (auto& s : to) s->sendText(msg);
}

std::vector<WsServer::ClientInfo> WsServer::clients() const {
  std::vector<std::shared_ptr<ClientSession>> all;
  std::map<uint32_t, std::string> topics;
  {
    std::lock_guard lk(mu_);
    for (const auto& [id, s] : sessions_) all.push_back(s);
    for (const auto& [id, c] : channels_) topics[id] = c.channel.topic;
  }
  std::vector<ClientInfo> out;
  for (const auto& s : all) out.push_back(s->info(topics));
  return out;
}

std::vector<Channel> WsServer::channelList() const {
  std::lock_guard lk(mu_);
  std::vector<Channel> out;
  for (const auto& [id, c] : channels_) out.push_back(c.channel);
  return out;
}

std::vector<Service> WsServer::serviceList() const {
  std::lock_guard lk(mu_);
  std::vector<Service> out;
  for (const auto& [id, s] : services_) out.push_back(s);
  return out;
}

bool WsServer::findService(uint32_t id, Service& out) const {
  std::lock_guard lk(mu_);
  const auto it = services_.find(id);
  if (it == services_.end()) return false;
  out = it->second;
  return true;
}

bool WsServer::channelExists(uint32_t id, Kind* kind) const {
  std::lock_guard lk(mu_);
  const auto it = channels_.find(id);
  if (it == channels_.end()) return false;
  if (kind) *kind = it->second.kind;
  return true;
}

void WsServer::attach(const std::shared_ptr<ClientSession>& s) {
  bool stopped;
  {
    // Under the lock: a channel added meanwhile is either in this list or
    // advertised to the session after it (addChannel copies the sessions under it).
    std::lock_guard lk(mu_);
    stopped = stopped_;
    if (!stopped) {
      sessions_[s->id()] = s;
      s->sendText(serverInfoJson(options_.name, capabilities(), {"json"}, session_id_));
      std::vector<Channel> channels;
      for (const auto& [id, c] : channels_) channels.push_back(c.channel);
      s->sendText(advertiseJson(channels));
      std::vector<Service> services;
      for (const auto& [id, sv] : services_) services.push_back(sv);
      if (!services.empty()) s->sendText(advertiseServicesJson(services));
    }
  }
  if (stopped) s->close();
}

void WsServer::detach(uint64_t client) {
  {
    std::lock_guard lk(mu_);
    if (sessions_.erase(client) == 0) return;
  }
  handler_.onClientClose(client);
}

std::shared_ptr<ClientSession> WsServer::find(uint64_t client) const {
  std::lock_guard lk(mu_);
  const auto it = sessions_.find(client);
  return it == sessions_.end() ? nullptr : it->second;
}

}  // namespace inspect::server::foxglove
