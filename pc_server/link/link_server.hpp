#pragma once
// The robot link's TCP side: the acceptor, the live sessions, robot id ->
// session (a new connection replaces an old one with the same id) and the
// command ids. Implements CommandSink for the console.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>

#include "pc_server/link/stored_events.hpp"
#include "pc_server/link/command_sink.hpp"
#include "shared/net/tls.hpp"
#include "pc_server/link/link_config.hpp"

namespace inspect::server {

class RobotRegistry;
class RobotSession;
class SessionThreads;

class LinkServer : public CommandSink {
 public:
  /// The acceptor runs on `ioc`; the sessions on `sessions`' threads, or on
  /// `ioc` too when null. Both must outlive the LinkServer, `sessions` must
  /// outlive `ioc` too (an accept pending there holds a socket of one of its
  /// io_contexts), and their threads must be stopped before anything an
  /// observer calls is destroyed.
  LinkServer(boost::asio::io_context& ioc, const LinkConfig& config, RobotRegistry& registry,
             SessionThreads* sessions = nullptr);
  ~LinkServer() override;
  LinkServer(const LinkServer&) = delete;
  LinkServer& operator=(const LinkServer&) = delete;

  /// Loads the TLS files (unless config.tls.plaintext), binds to
  /// config.bind_address:config.port and starts accepting. Throws util::StartupError.
  boost::asio::ip::tcp::endpoint listen();
  /// Stops accepting and closes every session; thread-safe, idempotent.
  void stop();
  /// Waits until every session has closed; false on timeout.
  bool waitAllClosed(std::chrono::steady_clock::duration timeout);
  /// The certificate the server presents ("" in plaintext mode), for the start-up line.
  const std::string& certificateInfo() const { return cert_info_; }
  /// Sessions open now (including those still in the handshake).
  std::size_t sessionCount() const;
  /// Whether robot events also go to the log (when no console shows them).
  void setLogEvents(bool on) { log_events_ = on; }
  bool logEvents() const { return log_events_; }

  uint64_t setTeleop(const std::string& robot_id, double v_m_s, double w_rad_s, double lease_s) override;
  void clearTeleop(const std::string& robot_id) override;
  void renewTeleop(const std::string& robot_id, double lease_s) override;
  uint64_t sendCommand(const std::string& robot_id, v1::Command cmd) override;
  void consoleAlive() override;

  /// When > 0: teleop re-sends stop (set-points clear) once consoleAlive() was not
  /// called for this long. 0 (default) = no console watchdog (tests, no console).
  void setConsoleWatchdog(std::chrono::milliseconds timeout);
  /// False when the console watchdog is on and the console went quiet.
  bool consoleResponsive() const;

  /// Called on a session's strand with every envelope of an accepted robot:
  /// `inbound` = from the robot (telemetry, events, acks; `time_us` = receive
  /// time) or to it (commands; `time_us` = send time); `address` is the
  /// robot's "ip:port". Heartbeats are left out. Set before listen().
  using EnvelopeObserver = std::function<void(const std::string& robot_id, const std::string& address,
                                              const v1::Envelope& env, bool inbound, uint64_t time_us)>;
  void addEnvelopeObserver(EnvelopeObserver f) { observers_.push_back(std::move(f)); }
  void observe(const std::string& robot_id, const std::string& address, const v1::Envelope& env, bool inbound,
               uint64_t time_us) const {
    for (const auto& f : observers_) f(robot_id, address, env, inbound, time_us);
  }

  /// Which stored events and acks of each robot were filed (store-and-forward).
  StoredEvents& storedEvents() { return stored_events_; }

  /// A fresh command id: > 0 and increasing over the server's lifetime.
  uint64_t nextCommandId() { return next_command_id_.fetch_add(1); }
  /// Called by a session whose Hello was accepted; closes an older session of the same robot.
  void attach(const std::string& robot_id, const std::shared_ptr<RobotSession>& session);
  /// Called by a session once it is closed.
  void detach(const std::shared_ptr<RobotSession>& session, const std::string& robot_id);

 private:
  void doAccept();
  std::shared_ptr<RobotSession> find(const std::string& robot_id) const;

  boost::asio::io_context& ioc_;
  SessionThreads* session_threads_;
  const LinkConfig config_;
  std::shared_ptr<boost::asio::ssl::context> tls_;  // null: plaintext
  std::string cert_info_;
  RobotRegistry& registry_;
  boost::asio::ip::tcp::acceptor acceptor_;  // on its own strand
  boost::asio::steady_timer accept_retry_timer_;
  std::atomic<uint64_t> next_command_id_{1};
  std::atomic<uint64_t> next_serial_{1};
  std::atomic<bool> log_events_{false};
  std::atomic<int64_t> console_watchdog_ns_{0};
  std::atomic<int64_t> console_alive_ns_{0};

  std::vector<EnvelopeObserver> observers_;
  StoredEvents stored_events_;

  mutable std::mutex mu_;
  std::condition_variable all_closed_cv_;
  bool stopped_ = false;
  std::set<std::shared_ptr<RobotSession>> live_;
  std::map<std::string, std::shared_ptr<RobotSession>> by_robot_;
};

}  // namespace inspect::server
