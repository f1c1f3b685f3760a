#pragma once
// pc_server as a Sparkplug B edge node (Eclipse Sparkplug 3.0.0; docs/sparkplug.md):
// the messages of one MQTT session, as a pure state machine. The node is
// born (NBIRTH, seq 0, the session's bdSeq) when the broker accepts it, each
// online robot is a device (DBIRTH with every metric), a change beyond its
// metric's deadband is DDATA, a robot that goes offline DDEATH; every later
// message takes the next seq (0-255, wrapping). The Will (NDEATH) carries
// the bdSeq of the session it ends; a lost session makes the next one's
// bdSeq the next (wrapping at 256). NCMD "Node Control/Rebirth" asks for
// the births again. No I/O and no clock: the caller passes the time (ms
// since the Unix epoch) and publishes what it returns.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pc_server/sparkplug/sparkplug_metric.hpp"

namespace inspect::server::sparkplug {

/// One MQTT message to publish.
struct Message {
  std::string topic;
  std::string payload;
  bool event = false;  // carries events (alarm transitions, command results): kept until the broker has it
};

class EdgeNode {
 public:
  EdgeNode(std::string group_id, std::string edge_node_id, uint8_t first_bd_seq = 0);

  const std::string& group() const { return group_; }
  const std::string& node() const { return node_; }
  uint8_t bdSeq() const { return bd_seq_; }
  bool born() const { return born_; }

  /// The Will to give the broker at CONNECT: NDEATH with this session's bdSeq.
  Message will(uint64_t now_ms) const;
  /// The NDEATH to publish before a clean disconnect (the same as the Will).
  Message death(uint64_t now_ms) const { return will(now_ms); }
  /// The broker accepted the session (or a rebirth was asked): NBIRTH, then
  /// a DBIRTH per online device with its latest metrics.
  std::vector<Message> birth(uint64_t now_ms);
  /// The session ended (lost or closed): nothing is published until the next
  /// birth, which has the next bdSeq.
  void sessionEnded();

  /// A device's metrics now (every one it has; the order of its DBIRTH). A
  /// device new or offline is born (DBIRTH); else the metrics that changed
  /// beyond their deadband are DDATA (none: no message). Not born: nothing
  /// (the values are kept for the next birth).
  std::optional<Message> update(const std::string& device, const std::vector<Metric>& metrics, uint64_t now_ms);
  /// Metrics of events (alarm transitions, timestamped) as DDATA at once,
  /// whatever the deadbands; their values become the device's too. Not born
  /// or the device not online: none (the caller keeps them).
  std::optional<Message> events(const std::string& device, const std::vector<Metric>& metrics, uint64_t now_ms);
  /// The device went offline: DDEATH (none when it was not born in this session).
  std::optional<Message> deviceOffline(const std::string& device, uint64_t now_ms);
  bool online(const std::string& device) const;

  /// An NCMD payload: whether it asks for a rebirth ("Node Control/Rebirth" true);
  /// nullopt = not a Sparkplug B payload.
  static std::optional<bool> rebirthAsked(const std::string& payload);

  static constexpr const char* kRebirth = "Node Control/Rebirth";
  static constexpr const char* kBdSeq = "bdSeq";

 private:
  struct Device {
    bool online = false;
    bool born = false;  // its DBIRTH went out in this session
    std::vector<Metric> latest;                 // every metric, the birth order
    std::map<std::string, Metric> published;    // the value hosts have now
  };
  int nextSeq();
  Message deviceBirth(const std::string& name, Device& d, uint64_t now_ms);
  static bool changed(const Metric& before, const Metric& now);

  std::string group_, node_;
  uint8_t bd_seq_;
  bool born_ = false;
  int seq_ = 0;  // the next message's
  std::map<std::string, Device> devices_;
};

}  // namespace inspect::server::sparkplug
