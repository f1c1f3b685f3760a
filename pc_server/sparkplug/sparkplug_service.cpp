#include "pc_server/sparkplug/sparkplug_service.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>

#include <nlohmann/json.hpp>

#include "pc_server/sparkplug/device_metrics.hpp"
#include "shared/util/clock.hpp"
#include "shared/util/log.hpp"

namespace inspect::server::sparkplug {

namespace {
uint64_t nowMs() { return wallNowNs() / 1'000'000; }  // Sparkplug's timestamps: UTC ms
constexpr int kStepMs = 20;  // the session's poll: an alarm transition waits at most this before it goes out
}  // namespace

SparkplugService::SparkplugService(const SparkplugConfig& cfg, std::string edge_node_id, const RobotRegistry& registry,
                                   std::function<std::string(const std::string&)> run_of, const std::string& spool_path)
    : cfg_(cfg), registry_(registry), run_of_(std::move(run_of)), node_(cfg.group_id, std::move(edge_node_id)) {
  if (!spool_path.empty()) {
    spool_ = std::make_unique<TransitionSpool>(spool_path);
    for (auto& t : spool_->all())  // an earlier process's, not confirmed: first, and late
      events_.push_back({std::move(t.device), std::move(t.alarm), t.time_ms, true, -1, t.seq});
    if (!events_.empty())
      log::info("sparkplug", events_.size(), " alarm transitions from ", spool_path, " not yet confirmed: sent first");
  }
  mqtt_.client_id = "inspect-" + cfg_.group_id + "-" + node_.node();
  mqtt_.host = cfg_.host;
  mqtt_.port = cfg_.port;
  mqtt_.keepalive_s = std::max(5, static_cast<int>(cfg_.keepalive_s));  // libmosquitto refuses 1-4 (config: [5, 600])
  mqtt_.ca = cfg_.ca;
  mqtt_.cert = cfg_.cert;
  mqtt_.key = cfg_.key;
  stats_.broker = cfg_.host + ":" + std::to_string(cfg_.port);
}

void SparkplugService::setCredentials(std::string username, std::string password) {
  mqtt_.username = std::move(username);
  mqtt_.password = std::move(password);
}

SparkplugService::~SparkplugService() { stop(); }

void SparkplugService::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] { run(); });
}

void SparkplugService::stop() {
  stop_ = true;
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

ServiceStats SparkplugService::stats() const {
  std::lock_guard lk(mu_);
  ServiceStats s = stats_;
  s.queued = events_.size();
  return s;
}

std::string SparkplugService::report() const {
  const ServiceStats st = stats();
  std::string r = "sparkplug: edge node " + node_.group() + "/" + node_.node() + " on mqtt" + (cfg_.ca.empty() ? "" : "s") +
                  "://" + st.broker + ": " + (st.connected ? "connected" : "not connected") + ", bdSeq " +
                  std::to_string(st.bd_seq) + ", " + std::to_string(st.sessions) + " sessions" +
                  (cfg_.primary_host_id.empty() ? "" : ", primary host " + cfg_.primary_host_id) + "\n";
  r += "  " + std::to_string(st.devices) + " robots online; " + std::to_string(st.published) +
       " messages published (QoS " + std::to_string(cfg_.qos) + ")\n";
  r += "  alarm transitions: " + std::to_string(st.events_sent) + " confirmed by the broker, " +
       std::to_string(st.queued) + " queued, " + std::to_string(st.dropped) + " dropped (queue_max " +
       std::to_string(cfg_.queue_max) + ")\n";
  r += "  DCMD: " + std::to_string(st.commands) + " received, " + std::to_string(st.commands_refused) + " refused; " +
       (cfg_.commands && ops_ ? "stop and e-stop allowed" : "commands off") + "\n";
  if (!st.error.empty()) r += "  last: " + st.error + "\n";
  return r;
}

uint64_t SparkplugService::wallMs(const std::string& robot, uint64_t robot_us) const {
  std::lock_guard lk(offsets_mu_);
  const auto it = offsets_us_.find(robot);
  if (it == offsets_us_.end()) return nowMs();
  return monoUsToWallNs(static_cast<uint64_t>(static_cast<int64_t>(robot_us) + it->second)) / 1'000'000;
}

void SparkplugService::onEnvelope(const std::string& robot, const v1::Envelope& env, bool inbound, uint64_t time_us) {
  if (!inbound) return;
  // The robot's clock (its telemetry's and its events' robot_time_us, from
  // its start) to the server's: the smallest (receive - robot time) seen is
  // the offset plus the shortest one-way delay. Every telemetry message of
  // every robot passes here, on the link's threads: a lock of its own, never
  // held across the spool's file.
  if (env.has_telemetry() && env.telemetry().robot_time_us()) {
    const int64_t o = static_cast<int64_t>(time_us) - static_cast<int64_t>(env.telemetry().robot_time_us());
    std::lock_guard lk(offsets_mu_);
    auto [it, fresh] = offsets_us_.try_emplace(robot, o);
    if (!fresh) it->second = std::min(it->second, o);
    return;
  }
  if (!env.has_event() || !env.event().has_gas_alarm()) return;
  const auto kind = env.event().kind();
  if (kind != v1::Event::ALARM_RAISED && kind != v1::Event::ALARM_CLEARED) return;
  const auto& a = env.event().gas_alarm();
  const uint64_t time_ms = wallMs(robot, a.robot_time_us() ? a.robot_time_us() : env.event().robot_time_us());
  std::lock_guard lk(mu_);
  if (events_.size() >= cfg_.queue_max) {
    ++stats_.dropped;
    log::warn("sparkplug", "event queue full (", cfg_.queue_max, "): alarm ", env.event().gas_alarm().id(), " of ",
              robot, " not sent");
    return;
  }
  // Late: stored by the robot, or it waits for the next session (it is not
  // the tags' current value when it arrives): historical data.
  QueuedEvent q{robot, a, time_ms, !live_ || (env.event().has_stored() && env.event().stored().replayed()), -1, 0};
  if (spool_) {
    try {
      q.spool_seq = spool_->append(q.device, q.alarm, q.time_ms, q.late);
    } catch (const std::exception& e) {
      log::warn("sparkplug", "alarm ", a.id(), " of ", robot, " kept in memory only: ", e.what());
    }
  }
  events_.push_back(std::move(q));
  wake_.notify_all();
}

void SparkplugService::run() {
  pthread_setname_np(pthread_self(), "sparkplug");  // top -H, link_load's per-thread CPU
  double backoff_s = 0.5;
  while (!stop_) {
    const uint32_t before = stats().sessions;
    session();
    if (stop_) break;
    if (stats().sessions != before) backoff_s = 0.5;  // it had been accepted: try again soon
    std::unique_lock lk(mu_);
    wake_.wait_for(lk, std::chrono::duration<double>(backoff_s), [this] { return stop_.load(); });
    backoff_s = std::min(backoff_s * 2, 5.0);
  }
}

void SparkplugService::session() {
  MqttSession* self = nullptr;
  MqttSession s(mqtt_, {[&](int rc) { onConnected(*self, rc); },
                        [&](int mid) {
                          last_delivered_mid_ = mid;
                          std::lock_guard lk(mu_);
                          const auto it = std::find_if(events_.begin(), events_.end(), [&](const QueuedEvent& e) { return e.mid == mid; });
                          if (it == events_.end()) return;  // a birth or data
                          confirmedLocked(it);
                        },
                        [&](const std::string& topic_name, const std::string& payload) {
                          if (!cfg_.primary_host_id.empty() && topic_name == "spBv1.0/STATE/" + cfg_.primary_host_id) {
                            onHostState(*self, payload);
                            return;
                          }
                          const std::string dcmd = topic(node_.group(), "DCMD", node_.node()) + "/";
                          if (topic_name.starts_with(dcmd) && node_.born()) {
                            onDeviceCommand(*self, topic_name.substr(dcmd.size()), payload);
                            return;
                          }
                          if (topic_name != topic(node_.group(), "NCMD", node_.node()) || !node_.born()) return;
                          if (EdgeNode::rebirthAsked(payload).value_or(false)) {
                            log::info("sparkplug", "NCMD Node Control/Rebirth: the births again");
                            publishDevices(*self, true);
                          }
                        }});
  self = &s;
  const Message will = node_.will(nowMs());
  if (const auto why = s.connect(will.topic, will.payload); !why.empty()) {
    std::lock_guard lk(mu_);
    if (stats_.error != why) log::warn("sparkplug", "broker ", stats_.broker, ": ", why);
    stats_.error = why;
    return;
  }
  auto next_data = std::chrono::steady_clock::now();
  const auto period = steadyDuration(std::max(0.02, cfg_.min_period_s));
  // A broker that never answers (its host drops the SYN, or it accepts the
  // TCP connection and says nothing) is given up after the keep-alive.
  const auto connack_by = std::chrono::steady_clock::now() + std::chrono::seconds(mqtt_.keepalive_s);
  std::string no_session;  // why this attempt never got a session
  while (!stop_ && s.step(kStepMs)) {
    if (!s.connected() && std::chrono::steady_clock::now() >= connack_by) {
      no_session = s.noAnswerText();
      break;
    }
    if (!node_.born()) continue;
    publishEvents(s);
    settleCommands(s);
    if (std::chrono::steady_clock::now() >= next_data) {
      publishDevices(s, false);
      next_data = std::chrono::steady_clock::now() + period;
    }
  }
  if (stop_ && node_.born() && !s.lost()) {
    // A clean end: the robots' deaths and the node's (the broker drops the Will).
    for (const auto& snap : registry_.snapshots(monoNowNs()))
      if (const auto m = node_.deviceOffline(snap.id, nowMs())) publish(s, *m);
    leave(s);
    if (!s.error().empty()) log::warn("sparkplug", "stopping: ", s.error());
  }
  if (no_session.empty() && !s.connected() && !stop_) no_session = s.error();
  const bool was_born = node_.born();
  node_.sessionEnded();
  std::lock_guard lk(mu_);
  if (!no_session.empty()) {
    if (stats_.error != no_session) log::warn("sparkplug", "broker ", stats_.broker, ": ", no_session);
    stats_.error = no_session;
  }
  live_ = false;
  for (auto& e : events_) {
    if (e.mid >= 0) e.late = true;  // the broker may not have it: again after the rebirth
    e.mid = -1;
  }
  stats_.connected = false;
  stats_.bd_seq = node_.bdSeq();
  if (was_born && !stop_) {
    stats_.error = s.error();
    log::warn("sparkplug", "broker ", stats_.broker, ": ", s.error(), "; ", events_.size(),
              " alarm transitions kept for the next session");
  }
}

void SparkplugService::onConnected(MqttSession& s, int rc) {
  if (rc != 0) {
    std::lock_guard lk(mu_);
    if (stats_.error != s.error()) log::warn("sparkplug", "broker ", stats_.broker, ": ", s.error());
    stats_.error = s.error();
    return;
  }
  s.subscribe(topic(node_.group(), "NCMD", node_.node()), 1);
  s.subscribe(topic(node_.group(), "DCMD", node_.node()) + "/+", 1);  // answered (refused) even when commands are off
  {
    std::lock_guard lk(mu_);
    ++stats_.sessions;
    stats_.connected = true;
    stats_.error.clear();
    stats_.bd_seq = node_.bdSeq();
  }
  if (!cfg_.primary_host_id.empty()) {
    // Births wait for the primary host's STATE online (retained; section 7.4).
    s.subscribe("spBv1.0/STATE/" + cfg_.primary_host_id, 1);
    log::info("sparkplug", "connected to ", cfg_.host, ":", cfg_.port, ": waiting for the primary host ",
              cfg_.primary_host_id);
    return;
  }
  birth(s);
}

void SparkplugService::birth(MqttSession& s) {
  publishDevices(s, true);
  std::lock_guard lk(mu_);
  live_ = true;
  log::info("sparkplug", "edge node ", node_.group(), "/", node_.node(), " born on ", stats_.broker, " (bdSeq ",
            static_cast<int>(node_.bdSeq()), ", ", events_.size(), " alarm transitions to send)");
}

void SparkplugService::onHostState(MqttSession& s, const std::string& payload) {
  // {"online": true|false, "timestamp": ms} (section 7.4.1).
  const auto j = nlohmann::json::parse(payload, nullptr, false);
  if (!j.is_object() || !j.contains("online") || !j["online"].is_boolean()) {
    log::warn("sparkplug", "STATE of the primary host ", cfg_.primary_host_id,
              " ignored: not JSON with a Boolean \"online\": ", payload.substr(0, 80));
    return;
  }
  const bool online = j["online"].get<bool>();
  if (online && !node_.born()) {
    birth(s);
  } else if (!online && node_.born()) {
    // The primary host went away: end this session (NDEATH) and start again, to be born when it is back.
    log::info("sparkplug", "the primary host ", cfg_.primary_host_id, " is offline: the edge node leaves the broker");
    leave(s);
  }
}

void SparkplugService::leave(MqttSession& s) {
  // NDEATH, then its PUBACK read (and so every earlier one) before the
  // DISCONNECT: a socket closed with a PUBACK unread is reset, and a broker
  // that sees the reset before the DISCONNECT publishes the Will as well.
  const Message death = node_.death(nowMs());
  const int mid = s.publish(death.topic, death.payload, 1);
  for (int i = 0; mid >= 0 && i < 100 && last_delivered_mid_ != mid && s.step(kStepMs); ++i) {
  }
  s.disconnect();
}

void SparkplugService::publishDevices(MqttSession& s, bool birth) {
  const uint64_t now = nowMs();
  uint32_t online = 0;
  std::vector<Message> out;
  for (const auto& snap : registry_.snapshots(monoNowNs())) {
    if (snap.connected && snap.has_telemetry) {
      ++online;
      const auto m = node_.update(snap.id, deviceMetrics(snap.hello, snap.telemetry, run_of_ ? run_of_(snap.id) : "",
                                                         cfg_.deadbands), now);
      if (m && !birth) out.push_back(*m);
    } else if (const auto m = node_.deviceOffline(snap.id, now)) {
      out.push_back(*m);
    }
  }
  if (birth) {
    const auto births = node_.birth(now);
    out.insert(out.begin(), births.begin(), births.end());
  }
  for (const auto& m : out)
    if (!publish(s, m)) return;
  std::lock_guard lk(mu_);
  stats_.devices = online;
}

void SparkplugService::publishEvents(MqttSession& s) {
  for (;;) {
    QueuedEvent e;
    {
      std::lock_guard lk(mu_);
      const auto it = std::find_if(events_.begin(), events_.end(), [](const QueuedEvent& q) { return q.mid < 0; });
      if (it == events_.end()) return;
      e = *it;
    }
    const uint64_t now = nowMs();
    const auto snap = registry_.snapshot(e.device, monoNowNs());
    const bool connected = snap && snap->connected;
    if (connected && !snap->has_telemetry) return;  // its first telemetry is on the way: born with it
    if (!node_.online(e.device)) {
      // Offline (it went during an outage, or it is an earlier process's
      // robot): born from its last telemetry, or with the alarm's metrics
      // alone, for its transitions, and dead again right after them.
      const auto metrics = snap && snap->has_telemetry ? deviceMetrics(snap->hello, snap->telemetry, "", cfg_.deadbands)
                                                       : alarmOnlyMetrics(e.alarm);
      if (const auto b = node_.update(e.device, metrics, now))
        if (!publish(s, *b)) return;
    }
    const auto m = node_.events(e.device, alarmEventMetrics(e.alarm, e.time_ms, e.late), now);
    if (!m) return;
    const int mid = s.publish(m->topic, m->payload, cfg_.qos);
    if (mid < 0) return;
    if (!connected)
      if (const auto d = node_.deviceOffline(e.device, now)) publish(s, *d);
    std::lock_guard lk(mu_);
    ++stats_.published;
    // The first not in flight is still `e` (only this thread sends; the link only appends).
    const auto it = std::find_if(events_.begin(), events_.end(), [](const QueuedEvent& q) { return q.mid < 0; });
    if (cfg_.qos == 0) {  // nothing will confirm it: sent is all there is
      confirmedLocked(it);
    } else {
      it->mid = mid;
    }
  }
}

void SparkplugService::confirmedLocked(std::deque<QueuedEvent>::iterator it) {
  if (spool_ && it->spool_seq) {
    try {
      spool_->remove(it->spool_seq);
    } catch (const std::exception& e) {
      log::warn("sparkplug", "the spool: ", e.what(), " (alarm ", it->alarm.id(), " may be sent again at the next start)");
    }
  }
  events_.erase(it);
  ++stats_.events_sent;
}

bool SparkplugService::publish(MqttSession& s, const Message& m) {
  if (s.publish(m.topic, m.payload, cfg_.qos) < 0) return false;
  std::lock_guard lk(mu_);
  ++stats_.published;
  return true;
}

void SparkplugService::answer(MqttSession& s, const std::string& device, const std::string& text) {
  const uint64_t now = nowMs();
  std::vector<Metric> m{Metric::ofString(kCommandResult, text)};
  m[0].timestamp_ms = now;
  if (const auto msg = node_.events(device, m, now)) publish(s, *msg);
}

void SparkplugService::onDeviceCommand(MqttSession& s, const std::string& device, const std::string& payload) {
  {
    std::lock_guard lk(mu_);
    ++stats_.commands;
  }
  const auto refuse = [&](const std::string& why) {
    {
      std::lock_guard lk(mu_);
      ++stats_.commands_refused;
    }
    log::warn("sparkplug", "DCMD for ", device, " refused: ", why);
    answer(s, device, "refused: " + why);
  };
  spb::Payload p;
  if (!p.ParseFromString(payload)) return refuse("not a Sparkplug B payload");
  for (const auto& m : p.metrics()) {
    const bool stop = m.name() == kCommandStop, estop = m.name() == kCommandEStop;
    if (!stop && !estop) {
      refuse("'" + m.name() + "' is not a command SCADA may give (" + kCommandStop + ", " + kCommandEStop + ")");
      continue;
    }
    if (!m.has_boolean_value() || !m.boolean_value()) {
      refuse(m.name() + " must be the Boolean true");
      continue;
    }
    if (!cfg_.commands || !ops_) {
      refuse("commands from SCADA are off on this server (sparkplug.commands)");
      continue;
    }
    log::info("sparkplug", "DCMD from SCADA: ", device, " ", estop ? "e-stop" : "stop");
    const Issued r = estop ? ops_->estop(ops_session_, device, monoNowNs()) : ops_->stop(ops_session_, device, monoNowNs());
    if (const auto* done = std::get_if<CallResult>(&r))
      answer(s, device, done->text());
    else
      pending_.push_back(std::get<PendingCall>(r));
  }
}

void SparkplugService::settleCommands(MqttSession& s) {
  for (auto it = pending_.begin(); it != pending_.end();) {
    const auto r = ops_ ? ops_->settle(*it, monoNowNs()) : std::nullopt;
    if (!r) {
      ++it;
      continue;
    }
    log::info("sparkplug", "DCMD answered: ", r->text());
    answer(s, it->robot, r->text());
    it = pending_.erase(it);
  }
}

}  // namespace inspect::server::sparkplug
