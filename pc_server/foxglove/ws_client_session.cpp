#include "pc_server/foxglove/ws_client_session.hpp"

#include "shared/util/log.hpp"

namespace inspect::server::foxglove {

namespace {
constexpr const char* kSessionTag = "foxglove";
}  // namespace

void ClientSession::endHandshake() {
  if (!handshaking_.exchange(false)) return;
  server_.handshakeEnded();
}

void ClientSession::deliver(uint32_t channel, WsServer::Kind kind, uint64_t ts, const std::shared_ptr<const std::string>& payload, bool keyframe) {
  {
    std::lock_guard lk(mu_);
    const auto it = by_channel_.find(channel);
    if (it == by_channel_.end()) return;
    OutMessage m{messageDataHeader(it->second, ts), payload, true, it->second};
    if (kind == WsServer::Kind::kVideo) queue_.pushVideo(it->second, keyframe, std::move(m));
    else queue_.pushData(std::move(m));
    const uint64_t dropped = queue_.dropped();
    if (dropped > warned_drops_ && Clock::now() - last_drop_warning_ > std::chrono::milliseconds(2500)) {
      // The same text as Foxglove's own bridges: the app shows a hint for it.
      warned_drops_ = dropped;
      last_drop_warning_ = Clock::now();
      queue_.pushControl(OutMessage{statusJson(StatusLevel::kWarning, "Send buffer limit reached"), nullptr, false});
    }
  }
  kick();
}

bool ClientSession::subscribedTo(uint32_t channel) const {
  std::lock_guard lk(mu_);
  return by_channel_.contains(channel);
}

void ClientSession::dropChannel(uint32_t channel) {
  std::lock_guard lk(mu_);
  const auto it = by_channel_.find(channel);
  if (it == by_channel_.end()) return;
  queue_.forgetStream(it->second);
  subs_.erase(it->second);
  by_channel_.erase(it);
}

WsServer::ClientInfo ClientSession::info(const std::map<uint32_t, std::string>& topics) const {
  std::lock_guard lk(mu_);
  WsServer::ClientInfo i;
  i.id = id_;
  i.peer = peer_;
  i.subprotocol = subprotocol_;
  i.connected_s = std::chrono::duration<double>(Clock::now() - since_).count();
  for (const auto& [ch, sub] : by_channel_)
    if (const auto t = topics.find(ch); t != topics.end()) i.subscriptions.push_back(t->second);
  for (const auto& [cid, c] : client_channels_) i.publishing.push_back(c.topic);
  i.queued_bytes = queue_.queuedBytes();
  i.queued_messages = queue_.queuedMessages();
  i.counters = queue_.counters();
  i.refused = refused_;
  return i;
}

void ClientSession::pushControl(OutMessage m) {
  bool ok;
  {
    std::lock_guard lk(mu_);
    ok = queue_.pushControl(std::move(m));
  }
  if (!ok) {
    log::warn(kSessionTag, "client ", id_, " (", peer_, ") reads nothing of its control replies: closed");
    close();
    return;
  }
  kick();
}

std::optional<OutMessage> ClientSession::nextOut() {
  std::lock_guard lk(mu_);
  return queue_.pop();
}

void ClientSession::greet() {
  server_.attach(shared_from_this());
  server_.handler().onClientOpen(id_, peer_);
}

void ClientSession::refuseAll(const std::string& op, const std::vector<std::string>& problems, StatusLevel level) {
  if (problems.empty()) return;
  std::string text = op + ": ";
  for (std::size_t i = 0; i < problems.size() && i < 3; ++i) text += (i ? "; " : "") + problems[i];
  if (problems.size() > 3) text += "; and " + std::to_string(problems.size() - 3) + " more";
  {
    std::lock_guard lk(mu_);
    refused_ += problems.size() - 1;  // refuse() counts one
  }
  refuse(text, level);
}

void ClientSession::refuse(const std::string& why, StatusLevel level) {
  {
    std::lock_guard lk(mu_);
    ++refused_;
  }
  sendText(statusJson(level, why));
}

bool ClientSession::withinRate() {
  const double now_s = std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
  switch (rate_.take(now_s)) {
    case RequestRateLimit::Verdict::kAllowed: return true;
    case RequestRateLimit::Verdict::kRefusedTell:
      refuse("too many requests: more than " + std::to_string(static_cast<int>(rate_.perSecond())) +
             " messages/s; messages are refused until the rate drops");
      return false;
    case RequestRateLimit::Verdict::kRefusedQuiet: break;
  }
  std::lock_guard lk(mu_);
  ++refused_;
  return false;
}

void ClientSession::onMessage(bool text, std::string_view bytes) {
  const Parsed p = text ? parseClientText(bytes) : parseClientBinary(bytes);
  // Urgent services (stop, e-stop) are never refused for the rate: a flood must not keep a robot moving.
  bool urgent = false;
  if (const auto* call = std::get_if<ServiceCallRequest>(&p.message); call && p.ok()) {
    Service sv;
    urgent = server_.findService(call->service_id, sv) && sv.urgent;
  }
  if (!urgent && !withinRate()) {
    if (const auto* call = std::get_if<ServiceCallRequest>(&p.message); call && p.ok())
      sendText(serviceCallFailureJson(call->service_id, call->call_id, "too many requests: call refused"));
    return;
  }
  if (!p.ok()) {
    refuse(p.error);
    return;
  }
  std::visit([&](const auto& m) { handle(m); }, p.message);
}

void ClientSession::handle(const Subscribe& s) {
  std::vector<std::string> problems;
  for (const auto& item : s.subscriptions) {
    std::string problem;
    {
      std::lock_guard lk(mu_);
      if (subs_.contains(item.id)) problem = "subscription id " + std::to_string(item.id) + " is already in use";
      else if (const auto c = by_channel_.find(item.channel_id); c != by_channel_.end())
        problem = "already subscribed to channel " + std::to_string(item.channel_id) + " (subscription " +
                  std::to_string(c->second) + ")";
    }
    if (problem.empty() && !server_.channelExists(item.channel_id))
      problem = "channel " + std::to_string(item.channel_id) + " is not advertised";
    if (!problem.empty()) {
      problems.push_back(problem + "; subscription ignored");
      continue;
    }
    {
      std::lock_guard lk(mu_);
      subs_[item.id] = item.channel_id;
      by_channel_[item.channel_id] = item.id;
    }
    server_.handler().onSubscribe(id_, item.channel_id);
  }
  if (problems.size() == 1) refuse(problems[0]);
  else refuseAll("subscribe", problems);
}

void ClientSession::handle(const Unsubscribe& u) {
  std::vector<std::string> problems;
  for (const uint32_t id : u.subscription_ids) {
    std::lock_guard lk(mu_);
    const auto it = subs_.find(id);
    if (it == subs_.end()) {
      problems.push_back("no subscription " + std::to_string(id));
      continue;
    }
    by_channel_.erase(it->second);
    queue_.forgetStream(id);
    subs_.erase(it);
  }
  refuseAll("unsubscribe", problems, StatusLevel::kWarning);
}

void ClientSession::handle(const ClientAdvertise& a) {
  std::vector<std::string> problems;
  for (const auto& c : a.channels) {
    std::string problem;
    if (c.encoding != "json") problem = "encoding '" + c.encoding.substr(0, 32) + "' is not supported (json)";
    else if (c.topic.empty() || c.topic.size() > 256) problem = "topic must be 1 to 256 characters";
    std::lock_guard lk(mu_);
    if (problem.empty() && client_channels_.contains(c.id))
      problem = "client channel " + std::to_string(c.id) + " is already advertised";
    if (problem.empty() && client_channels_.size() >= 64) problem = "at most 64 client channels";
    if (!problem.empty()) {
      problems.push_back("channel " + std::to_string(c.id) + ": " + problem);
      continue;
    }
    client_channels_[c.id] = c;
  }
  refuseAll("advertise", problems);
}

void ClientSession::handle(const ClientUnadvertise& u) {
  std::vector<std::string> problems;
  for (const uint32_t id : u.channel_ids) {
    std::lock_guard lk(mu_);
    if (client_channels_.erase(id) == 0) problems.push_back("client channel " + std::to_string(id) + " was not advertised");
  }
  refuseAll("unadvertise", problems, StatusLevel::kWarning);
}

void ClientSession::handle(const ClientMessageData& d) {
  std::optional<ClientChannel> ch;
  {
    std::lock_guard lk(mu_);
    if (const auto it = client_channels_.find(d.channel_id); it != client_channels_.end()) ch = it->second;
  }
  if (!ch) {
    refuse("message on client channel " + std::to_string(d.channel_id) + ", which this client did not advertise");
    return;
  }
  server_.handler().onClientMessage(id_, *ch, d.payload);
}

void ClientSession::handle(const ServiceCallRequest& r) {
  Service s;
  if (!server_.findService(r.service_id, s)) {
    {
      std::lock_guard lk(mu_);
      ++refused_;
    }
    sendText(serviceCallFailureJson(r.service_id, r.call_id, "no service " + std::to_string(r.service_id)));
    return;
  }
  if (r.encoding != "json") {
    {
      std::lock_guard lk(mu_);
      ++refused_;
    }
    sendText(serviceCallFailureJson(r.service_id, r.call_id,
                                    "encoding '" + r.encoding.substr(0, 32) + "' is not supported (json)"));
    return;
  }
  server_.handler().onServiceCall(id_, s, r.call_id, r.payload);
}

void ClientSession::handle(const UnsupportedOp& u) {
  refuse("op '" + u.op + "' needs the capability '" + u.capability + "', which this server does not offer");
}

}  // namespace inspect::server::foxglove
