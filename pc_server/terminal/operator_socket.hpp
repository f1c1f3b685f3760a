#pragma once
// More operator consoles beside the server's own: a Unix-domain socket
// (--operator-socket PATH, mode 0660) that `pc_server --attach PATH` (or any
// line client) connects to. Each connection is a console session of its own,
// named after the connecting user (SO_PEERCRED), running on its own thread:
// it sees every robot, its events and runs; its motion commands need the
// robot's control (ControlArbiter). File permissions are the authentication:
// operators log in to the PC (e.g. over ssh) to attach.
#include <atomic>
#include <chrono>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "pc_server/console/console.hpp"

namespace inspect::server {

class OperatorSocket {
 public:
  /// Completes a session's console (video, recorder, tuning paths) before it runs.
  using Configure = std::function<void(Console&)>;

  OperatorSocket(std::string path, RobotRegistry& registry, CommandSink& sink, ControlArbiter& control,
                 Console::Options options, Configure configure);
  ~OperatorSocket();
  OperatorSocket(const OperatorSocket&) = delete;
  OperatorSocket& operator=(const OperatorSocket&) = delete;

  /// Creates the socket (a stale one from a dead server is replaced; a live
  /// server's is not) and starts accepting. Throws util::StartupError.
  void start();
  /// Ends every session (their waits are interrupted) and removes the socket.
  void stop();
  int sessionCount() const { return live_.load(); }

  /// Longest accepted command line; longer lines are refused and skipped.
  static constexpr std::size_t kMaxLine = 4096;
  /// At most this many sessions at once; more are told so and closed.
  static constexpr int kMaxSessions = 16;
  /// An attached session's `drive` set-point lapses this long after its last
  /// line or keep-alive (`pc_server --attach` sends one every kKeepAlivePeriod).
  static constexpr double kDriveLease_s = 0.3;
  static constexpr std::chrono::milliseconds kKeepAlivePeriod{100};

 private:
  struct Session {
    int fd = -1;
    StopFlag stop;
    std::thread thread;
    std::atomic<bool> done{false};
  };
  void acceptLoop();
  void runSession(Session& s);

  std::string path_;
  RobotRegistry& registry_;
  CommandSink& sink_;
  ControlArbiter& control_;
  Console::Options options_;
  Configure configure_;
  int listen_fd_ = -1;
  std::atomic<bool> stopping_{false};
  std::atomic<int> live_{0};
  std::thread acceptor_;
  std::mutex mu_;
  std::list<std::unique_ptr<Session>> sessions_;
};

/// `pc_server --attach PATH`: stdin lines to the session, its output to stdout,
/// until either side ends. Returns the exit status (0, or 3 when it cannot connect).
int attachToOperatorSocket(const std::string& path);

}  // namespace inspect::server
