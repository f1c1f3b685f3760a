#include "pc_server/robot_registry.hpp"

#include <algorithm>

namespace inspect::server {

RobotRegistry::Entry* RobotRegistry::current(const std::string& id, uint64_t serial) {
  const auto it = robots_.find(id);
  if (it == robots_.end() || it->second.serial != serial || !it->second.connected) return nullptr;
  return &it->second;
}

void RobotRegistry::onConnected(const std::string& id, const std::string& address, uint64_t serial,
                                const v1::Hello& hello, int64_t now_ns) {
  std::lock_guard lk(mu_);
  Entry& e = robots_[id];
  e.serial = serial;
  e.connected = true;
  e.connect_order = ++connect_counter_;
  e.address = address;
  e.software_version = hello.software_version();
  e.capabilities.assign(hello.capabilities().begin(), hello.capabilities().end());
  e.state_change_ns = now_ns;
  e.close_reason.clear();
  e.rx_times_ns.clear();
}

void RobotRegistry::onDisconnected(const std::string& id, uint64_t serial, const std::string& reason,
                                   int64_t now_ns) {
  std::lock_guard lk(mu_);
  Entry* e = current(id, serial);
  if (!e) return;
  e->connected = false;
  e->state_change_ns = now_ns;
  e->close_reason = reason;
}

void RobotRegistry::onTelemetry(const std::string& id, uint64_t serial, const v1::Telemetry& t, int64_t now_ns) {
  std::lock_guard lk(mu_);
  Entry* e = current(id, serial);
  if (!e) return;
  e->telemetry = t;
  e->has_telemetry = true;
  e->telemetry_rx_ns = now_ns;
  ++e->telemetry_count;
  e->rx_times_ns.push_back(now_ns);
  while (!e->rx_times_ns.empty() && e->rx_times_ns.front() <= now_ns - kRateWindowNs) e->rx_times_ns.pop_front();
}

void RobotRegistry::onEvent(const std::string& id, uint64_t serial, const v1::Event& ev) {
  std::lock_guard lk(mu_);
  Entry* e = current(id, serial);
  if (!e) return;
  e->events.push_back(ev);
  if (e->events.size() > kMaxEventsPerRobot) e->events.pop_front();
  pending_.push_back({id, ev});
  if (pending_.size() > kMaxPendingEvents) {
    pending_.pop_front();
    ++dropped_events_;
  }
}

void RobotRegistry::onAck(const std::string& id, uint64_t serial, const v1::Ack& a) {
  std::lock_guard lk(mu_);
  Entry* e = current(id, serial);
  if (!e) return;
  e->acks[a.command_id()] = a;
  // Command ids increase, so the smallest ids are the oldest.
  while (e->acks.size() > kMaxAcksPerRobot) e->acks.erase(e->acks.begin());
}

RobotSnapshot RobotRegistry::makeSnapshot(const std::string& id, const Entry& e, int64_t now_ns) const {
  RobotSnapshot s;
  s.id = id;
  s.connected = e.connected;
  s.address = e.address;
  s.software_version = e.software_version;
  s.capabilities = e.capabilities;
  s.has_telemetry = e.has_telemetry;
  if (e.has_telemetry) {
    s.telemetry = e.telemetry;
    s.telemetry_age_s = static_cast<double>(now_ns - e.telemetry_rx_ns) * 1e-9;
  }
  s.telemetry_count = e.telemetry_count;
  const int64_t from = now_ns - kRateWindowNs;
  const auto n = std::count_if(e.rx_times_ns.begin(), e.rx_times_ns.end(), [&](int64_t t) { return t > from; });
  // Right after connecting the window is shorter than a second; the 0.2 s floor keeps one early
  // message from reading as a huge rate.
  const double span_s = std::clamp(static_cast<double>(now_ns - e.state_change_ns) * 1e-9, 0.2, 1.0);
  s.telemetry_hz = e.connected || n > 0 ? static_cast<double>(n) / (e.connected ? span_s : 1.0) : 0.0;
  s.state_age_s = static_cast<double>(now_ns - e.state_change_ns) * 1e-9;
  s.close_reason = e.close_reason;
  return s;
}

std::optional<RobotSnapshot> RobotRegistry::snapshot(const std::string& id, int64_t now_ns) const {
  std::lock_guard lk(mu_);
  const auto it = robots_.find(id);
  if (it == robots_.end()) return std::nullopt;
  return makeSnapshot(id, it->second, now_ns);
}

std::vector<RobotSnapshot> RobotRegistry::snapshots(int64_t now_ns) const {
  std::lock_guard lk(mu_);
  std::vector<RobotSnapshot> out;
  out.reserve(robots_.size());
  for (const auto& [id, e] : robots_) out.push_back(makeSnapshot(id, e, now_ns));
  return out;
}

int RobotRegistry::connectedCount() const {
  std::lock_guard lk(mu_);
  return static_cast<int>(std::count_if(robots_.begin(), robots_.end(), [](const auto& kv) { return kv.second.connected; }));
}

std::string RobotRegistry::firstConnected() const {
  std::lock_guard lk(mu_);
  const Entry* best = nullptr;
  std::string id;
  for (const auto& [k, e] : robots_) {
    if (e.connected && (!best || e.connect_order < best->connect_order)) {
      best = &e;
      id = k;
    }
  }
  return id;
}

std::optional<v1::Ack> RobotRegistry::ack(const std::string& id, uint64_t command_id) const {
  std::lock_guard lk(mu_);
  const auto it = robots_.find(id);
  if (it == robots_.end()) return std::nullopt;
  const auto a = it->second.acks.find(command_id);
  if (a == it->second.acks.end()) return std::nullopt;
  return a->second;
}

std::vector<PendingEvent> RobotRegistry::takeEvents() {
  std::lock_guard lk(mu_);
  std::vector<PendingEvent> out(std::make_move_iterator(pending_.begin()), std::make_move_iterator(pending_.end()));
  pending_.clear();
  return out;
}

uint64_t RobotRegistry::droppedEvents() const {
  std::lock_guard lk(mu_);
  return dropped_events_;
}

std::vector<v1::Event> RobotRegistry::events(const std::string& id) const {
  std::lock_guard lk(mu_);
  const auto it = robots_.find(id);
  if (it == robots_.end()) return {};
  return {it->second.events.begin(), it->second.events.end()};
}

}  // namespace inspect::server
