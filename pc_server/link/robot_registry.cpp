#include "pc_server/link/robot_registry.hpp"

#include <algorithm>

namespace inspect::server {

namespace {
// One occurrence: the robot's id, and its channel and level (ids start over
// when robot_client restarts).
bool sameAlarm(const v1::GasAlarm& a, const v1::GasAlarm& b) {
  return a.id() == b.id() && a.channel() == b.channel() && a.level() == b.level();
}
}  // namespace

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
  e.hello = hello;
  if (hello.has_gains()) noteGainsLocked(e, hello.gains(), hello.gains_version());
}

void RobotRegistry::noteGainsLocked(Entry& e, const v1::Gains& g, uint32_t version) {
  if (e.gains_known && e.gains_version == version &&
      e.gains.SerializeAsString() == g.SerializeAsString())
    return;  // the same set again (a reconnect)
  if (e.gains_known) {
    e.gains_history.emplace_back(e.gains_version, e.gains);
    if (e.gains_history.size() > kMaxGainsHistory) e.gains_history.erase(e.gains_history.begin());
  }
  e.gains_known = true;
  e.gains = g;
  e.gains_version = version;
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
  // Resync the alarm book with the alarms the robot says are in force (a
  // raise or clear event lost across a reconnect or a server restart).
  for (const auto& a : t.active_alarms()) {
    bool known = false;
    for (auto& r : alarms_) {
      if (r.robot_id != id || !r.active() || !sameAlarm(r.alarm, a)) continue;
      known = true;
      // The reading now and the worst so far; where and when it was raised stay.
      r.alarm.set_value(a.value());
      r.alarm.set_peak(a.peak());
    }
    if (!known) {
      noteAlarmLocked(id, a, now_ns);
      // Its raise event never came (link down, server restarted): say so on the console.
      v1::Event ev;
      ev.set_kind(v1::Event::ALARM_RAISED);
      ev.set_text("gas " + a.channel_name() + " " + v1::GasAlarm::Level_Name(a.level()) +
                  (a.fault().empty() ? "" : " " + a.fault()) +
                  " alarm in force (learnt from telemetry: its raise event was not received)");
      *ev.mutable_gas_alarm() = a;
      pushEventLocked(id, ev);
    }
  }
  for (auto& r : alarms_) {
    if (e->active_alarms == 0) break;
    if (r.robot_id != id || !r.active()) continue;
    bool listed = false;
    for (const auto& a : t.active_alarms()) listed |= sameAlarm(a, r.alarm);
    if (!listed && now_ns - r.raised_ns > 1'000'000'000) {  // not a raise still in flight
      r.cleared_ns = now_ns;
      r.alarm.set_active(false);
      --e->active_alarms;
    }
  }
  e->rx_times_ns.push_back(now_ns);
  while (!e->rx_times_ns.empty() && e->rx_times_ns.front() <= now_ns - kRateWindowNs) e->rx_times_ns.pop_front();
}

void RobotRegistry::noteAlarmLocked(const std::string& id, const v1::GasAlarm& a, int64_t now_ns) {
  for (auto it = alarms_.rbegin(); it != alarms_.rend(); ++it) {
    if (it->robot_id != id || !it->active() || !sameAlarm(it->alarm, a)) continue;
    // The clear brings the reading then and the worst one; where the alarm was
    // raised (pose) and its threshold stay those of the raise.
    const v1::Pose2D raised_at = it->alarm.pose();
    it->alarm = a;
    if (!a.active()) {
      it->cleared_ns = now_ns;
      *it->alarm.mutable_pose() = raised_at;
      --robots_[id].active_alarms;
    }
    return;
  }
  if (!a.active()) return;  // the clear of an alarm never seen raised (or already resynced away)
  AlarmRecord r;
  r.number = ++alarm_counter_;
  r.robot_id = id;
  r.alarm = a;
  r.raised_ns = now_ns;
  alarms_.push_back(std::move(r));
  ++robots_[id].active_alarms;
  // Drop the oldest finished ones beyond the bound (active alarms are never dropped).
  while (alarms_.size() > kMaxAlarms) {
    auto it = std::find_if(alarms_.begin(), alarms_.end(), [](const AlarmRecord& x) { return !x.active(); });
    if (it == alarms_.end()) break;
    alarms_.erase(it);
  }
}

std::vector<AlarmRecord> RobotRegistry::alarms(bool all, const std::string& robot_id) const {
  std::lock_guard lk(mu_);
  std::vector<AlarmRecord> out;
  for (const auto& r : alarms_)
    if ((all || r.active() || !r.acked) && (robot_id.empty() || r.robot_id == robot_id)) out.push_back(r);
  return out;
}

std::optional<AlarmRecord> RobotRegistry::ackAlarm(int number, int64_t now_ns) {
  std::lock_guard lk(mu_);
  for (auto& r : alarms_) {
    if (r.number != number) continue;
    if (!r.acked) {
      r.acked = true;
      r.acked_ns = now_ns;
    }
    return r;
  }
  return std::nullopt;
}

std::vector<AlarmRecord> RobotRegistry::ackAllAlarms(int64_t now_ns) {
  std::lock_guard lk(mu_);
  std::vector<AlarmRecord> out;
  for (auto& r : alarms_) {
    if (r.acked) continue;
    r.acked = true;
    r.acked_ns = now_ns;
    out.push_back(r);
  }
  return out;
}

int RobotRegistry::unackedAlarms(const std::string& robot_id) const {
  std::lock_guard lk(mu_);
  int n = 0;
  for (const auto& r : alarms_) n += r.active() && !r.acked && (robot_id.empty() || r.robot_id == robot_id);
  return n;
}

void RobotRegistry::onEvent(const std::string& id, uint64_t serial, const v1::Event& ev, int64_t now_ns) {
  std::lock_guard lk(mu_);
  Entry* e = current(id, serial);
  if (!e) return;
  if (ev.has_gas_alarm()) noteAlarmLocked(id, ev.gas_alarm(), now_ns);
  if (ev.kind() == v1::Event::GAINS_APPLIED && ev.has_gains()) noteGainsLocked(*e, ev.gains(), ev.gains_version());
  e->events.push_back(ev);
  if (e->events.size() > kMaxEventsPerRobot) e->events.pop_front();
  pushEventLocked(id, ev);
}

void RobotRegistry::onAck(const std::string& id, uint64_t serial, const v1::Ack& a) {
  {
    std::lock_guard lk(mu_);
    Entry* e = current(id, serial);
    if (!e) return;
    e->acks[a.command_id()] = a;
    // Command ids increase, so the smallest ids are the oldest.
    while (e->acks.size() > kMaxAcksPerRobot) e->acks.erase(e->acks.begin());
  }
  ack_signal_.notify();
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
  s.gains_known = e.gains_known;
  s.gains = e.gains;
  s.gains_version = e.gains_version;
  s.gains_history = e.gains_history;
  s.hello = e.hello;
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

void RobotRegistry::pushEventLocked(const std::string& id, const v1::Event& ev) {
  pending_.push_back({id, ev});
  if (pending_.size() > kMaxPendingEvents) {
    pending_.pop_front();
    ++first_event_;
  }
}

std::vector<PendingEvent> RobotRegistry::takeEvents() {
  std::lock_guard lk(mu_);
  uint64_t missed = 0;
  auto out = eventsSinceLocked(take_cursor_, &missed);
  dropped_events_ += missed;
  return out;
}

uint64_t RobotRegistry::droppedEvents() const {
  std::lock_guard lk(mu_);
  return dropped_events_;
}

uint64_t RobotRegistry::eventCursor() const {
  std::lock_guard lk(mu_);
  return first_event_ + pending_.size();
}

std::vector<PendingEvent> RobotRegistry::eventsSince(uint64_t& cursor, uint64_t* missed) const {
  std::lock_guard lk(mu_);
  return eventsSinceLocked(cursor, missed);
}

std::vector<PendingEvent> RobotRegistry::eventsSinceLocked(uint64_t& cursor, uint64_t* missed) const {
  if (missed) *missed = cursor < first_event_ ? first_event_ - cursor : 0;
  const uint64_t end = first_event_ + pending_.size();
  std::vector<PendingEvent> out;
  for (uint64_t i = std::max(cursor, first_event_); i < end; ++i) out.push_back(pending_[i - first_event_]);
  cursor = end;
  return out;
}

std::vector<v1::Event> RobotRegistry::events(const std::string& id) const {
  std::lock_guard lk(mu_);
  const auto it = robots_.find(id);
  if (it == robots_.end()) return {};
  return {it->second.events.begin(), it->second.events.end()};
}

}  // namespace inspect::server
