#include "pc_server/sparkplug/edge_node.hpp"

#include <cmath>
#include <utility>

namespace inspect::server::sparkplug {

EdgeNode::EdgeNode(std::string group_id, std::string edge_node_id, uint8_t first_bd_seq)
    : group_(std::move(group_id)), node_(std::move(edge_node_id)), bd_seq_(first_bd_seq) {}

int EdgeNode::nextSeq() {
  const int s = seq_;
  seq_ = (seq_ + 1) % 256;  // section 7.2: 0-255, then 0 again
  return s;
}

Message EdgeNode::will(uint64_t now_ms) const {
  // NDEATH: the bdSeq metric alone, no seq (section 7.1.1).
  return {topic(group_, "NDEATH", node_), encodePayload({Metric::ofUInt64(kBdSeq, bd_seq_)}, now_ms, -1), false};
}

std::vector<Message> EdgeNode::birth(uint64_t now_ms) {
  born_ = true;
  seq_ = 0;
  std::vector<Message> out;
  out.push_back({topic(group_, "NBIRTH", node_),
                 encodePayload({Metric::ofUInt64(kBdSeq, bd_seq_), Metric::ofBool(kRebirth, false)}, now_ms, nextSeq()),
                 false});
  for (auto& [name, d] : devices_) {
    d.born = false;
    if (d.online) out.push_back(deviceBirth(name, d, now_ms));
  }
  return out;
}

void EdgeNode::sessionEnded() {
  if (!born_) return;
  born_ = false;
  bd_seq_ = static_cast<uint8_t>(bd_seq_ + 1);  // the next session's (0-255, wrapping)
  for (auto& [name, d] : devices_) d.born = false;
}

Message EdgeNode::deviceBirth(const std::string& name, Device& d, uint64_t now_ms) {
  d.born = true;
  d.published.clear();
  for (const auto& m : d.latest) d.published[m.name] = m;
  return {topic(group_, "DBIRTH", node_, name), encodePayload(d.latest, now_ms, nextSeq()), false};
}

bool EdgeNode::changed(const Metric& before, const Metric& now) {
  if (before.type != now.type || before.isNull() != now.isNull()) return true;
  if (now.isNull()) return false;
  if (now.type == DataType::kDouble)
    return std::abs(std::get<double>(now.value) - std::get<double>(before.value)) > now.deadband;
  return before.value != now.value;
}

std::optional<Message> EdgeNode::update(const std::string& device, const std::vector<Metric>& metrics,
                                        uint64_t now_ms) {
  Device& d = devices_[device];
  const bool was_online = d.online;
  d.online = true;
  d.latest = metrics;
  if (!born_) return std::nullopt;
  if (!was_online || !d.born) return deviceBirth(device, d, now_ms);
  std::vector<Metric> changes;
  for (const auto& m : metrics) {
    if (m.event_driven) continue;  // its transitions come as events()
    const auto it = d.published.find(m.name);
    if (it == d.published.end() || changed(it->second, m)) {
      changes.push_back(m);
      d.published[m.name] = m;
    }
  }
  if (changes.empty()) return std::nullopt;
  return Message{topic(group_, "DDATA", node_, device), encodePayload(changes, now_ms, nextSeq()), false};
}

std::optional<Message> EdgeNode::events(const std::string& device, const std::vector<Metric>& metrics,
                                        uint64_t now_ms) {
  const auto it = devices_.find(device);
  if (!born_ || it == devices_.end() || !it->second.born || metrics.empty()) return std::nullopt;
  Device& d = it->second;
  for (const auto& m : metrics) {
    if (m.historical) continue;  // a past value is not the tag's current one
    d.published[m.name] = m;
    for (auto& l : d.latest)
      if (l.name == m.name) l = m;
  }
  return Message{topic(group_, "DDATA", node_, device), encodePayload(metrics, now_ms, nextSeq()), true};
}

std::optional<Message> EdgeNode::deviceOffline(const std::string& device, uint64_t now_ms) {
  const auto it = devices_.find(device);
  if (it == devices_.end() || !it->second.online) return std::nullopt;
  it->second.online = false;
  const bool announced = born_ && it->second.born;
  it->second.born = false;
  if (!announced) return std::nullopt;
  return Message{topic(group_, "DDEATH", node_, device), encodePayload({}, now_ms, nextSeq()), false};
}

bool EdgeNode::online(const std::string& device) const {
  const auto it = devices_.find(device);
  return it != devices_.end() && it->second.online;
}

std::optional<bool> EdgeNode::rebirthAsked(const std::string& payload) {
  spb::Payload p;
  if (!p.ParseFromString(payload)) return std::nullopt;
  for (const auto& m : p.metrics())
    if (m.name() == kRebirth && m.has_boolean_value() && m.boolean_value()) return true;
  return false;
}

}  // namespace inspect::server::sparkplug
