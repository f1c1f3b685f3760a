#pragma once
// The Sparkplug B edge node at work (docs/sparkplug.md): a thread of its own
// keeps one MQTT session to the broker (a new one after a loss, with the
// next bdSeq, backing off 0.5-5 s), publishes the node's and each robot's
// births, their data every min_period_s beyond the deadbands, the robots'
// deaths, and every gas alarm transition the link brings, at the robot's
// time. Alarm transitions are kept in order until the broker has them
// (PUBACK): those of an outage, or in flight when the session was lost, go
// out after the rebirth, as historical data. Fed by the link's envelopes
// (any thread) and the registry; answers NCMD rebirth.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/operator_service.hpp"
#include "pc_server/sparkplug/edge_node.hpp"
#include "pc_server/sparkplug/mqtt_session.hpp"
#include "pc_server/sparkplug/sparkplug_config.hpp"
#include "pc_server/sparkplug/transition_spool.hpp"

namespace inspect::server::sparkplug {

/// Figures for `sparkplug` on the console and the benchmarks.
struct ServiceStats {
  bool connected = false;
  std::string broker;        // host:port
  std::string error;         // the last session's end or refusal ("" = none)
  uint32_t sessions = 0;     // sessions the broker accepted
  uint8_t bd_seq = 0;
  uint64_t published = 0;    // messages
  uint64_t events_sent = 0;  // alarm transitions the broker confirmed
  std::size_t queued = 0;    // alarm transitions waiting for the broker
  uint64_t dropped = 0;      // transitions lost to a full queue (queue_max)
  uint64_t commands = 0;     // DCMD messages received
  uint64_t commands_refused = 0;
  uint32_t devices = 0;      // robots online
};

class SparkplugService {
 public:
  /// `run_of`: the run being recorded for a robot ("" = none); may be empty.
  /// `spool_path`: the file the alarm transitions are kept in until the
  /// broker confirms them ("" = memory only); what an earlier process left
  /// there goes out first, as historical data. Throws catalog::CatalogError
  /// when the file cannot be used.
  SparkplugService(const SparkplugConfig& cfg, std::string edge_node_id, const RobotRegistry& registry,
                   std::function<std::string(const std::string&)> run_of = {}, const std::string& spool_path = "");
  ~SparkplugService();
  SparkplugService(const SparkplugService&) = delete;
  SparkplugService& operator=(const SparkplugService&) = delete;

  /// DCMD from SCADA (sparkplug.commands): stop and e-stop only, through
  /// `ops` as `session` (an operator session of its own: any session may stop
  /// a robot, none may move one from here). Not set, or commands off: every
  /// DCMD is refused, and the refusal answered. Set before start().
  void setCommands(OperatorService* ops, uint64_t session) {
    ops_ = ops;
    ops_session_ = session;
  }
  /// The broker's user name and password (from credentials_file; never the command line).
  void setCredentials(std::string username, std::string password);
  void start();
  /// Publishes the robots' DDEATH and the node's NDEATH, disconnects, joins.
  void stop();

  /// A link envelope (LinkServer's observer): clock offsets, alarm transitions.
  void onEnvelope(const std::string& robot, const v1::Envelope& env, bool inbound, uint64_t time_us);

  ServiceStats stats() const;
  /// The console's `sparkplug` lines.
  std::string report() const;

 private:
  struct QueuedEvent {
    std::string device;
    v1::GasAlarm alarm;
    uint64_t time_ms = 0;
    bool late = false;  // stored by the robot, or held across an outage: historical
    int mid = -1;       // in flight under this message id
    int64_t spool_seq = 0;  // its row in the spool (0 = none)
  };
  /// The broker confirmed it (or QoS 0 sent it): out of the queue and the spool; mu_ held.
  void confirmedLocked(std::deque<QueuedEvent>::iterator it);
  void run();
  void session();
  void onConnected(MqttSession& s, int rc);
  /// NBIRTH and the robots' DBIRTH.
  void birth(MqttSession& s);
  /// NDEATH and a clean DISCONNECT (the broker drops the Will).
  void leave(MqttSession& s);
  /// The primary host's STATE message: born when online, the session ended when offline.
  void onHostState(MqttSession& s, const std::string& payload);
  /// Every robot's data beyond the deadbands, and DDEATH of those gone;
  /// `birth`: the node's and the robots' births instead (a new session, a rebirth).
  void publishDevices(MqttSession& s, bool birth);
  /// The alarm transitions not in flight, in order.
  void publishEvents(MqttSession& s);
  bool publish(MqttSession& s, const Message& m);
  uint64_t wallMs(const std::string& robot, uint64_t robot_us) const;
  /// A DCMD for `device`: stop / e-stop issued, anything else refused; answered in DDATA.
  void onDeviceCommand(MqttSession& s, const std::string& device, const std::string& payload);
  /// Answers the calls whose Ack came in or whose time ran out.
  void settleCommands(MqttSession& s);
  void answer(MqttSession& s, const std::string& device, const std::string& text);

  SparkplugConfig cfg_;
  MqttOptions mqtt_;
  const RobotRegistry& registry_;
  std::function<std::string(const std::string&)> run_of_;
  EdgeNode node_;  // the thread's alone
  OperatorService* ops_ = nullptr;
  uint64_t ops_session_ = 0;
  std::vector<PendingCall> pending_;  // DCMD calls waiting for the robot's Ack (the thread's alone)
  int last_delivered_mid_ = -1;       // the session's latest PUBACK (the thread's alone)
  std::thread thread_;
  std::atomic<bool> stop_{false};

  mutable std::mutex mu_;  // what follows, up to offsets_mu_
  std::condition_variable wake_;
  std::deque<QueuedEvent> events_;
  std::unique_ptr<TransitionSpool> spool_;  // null: memory only
  bool live_ = false;  // born on the broker now: a transition goes out at once
  ServiceStats stats_;

  mutable std::mutex offsets_mu_;  // offsets_us_ alone: taken for every telemetry message
  std::map<std::string, int64_t> offsets_us_;  // per robot: server monotonic - robot clock (smallest seen)
};

}  // namespace inspect::server::sparkplug
