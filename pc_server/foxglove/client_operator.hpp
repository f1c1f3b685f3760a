#pragma once
// A Foxglove client as an operator session (docs/foxglove.md): a Console of
// its own, a session of the ControlArbiter like any attached console, and a
// worker thread that runs its service calls one at a time (a console command
// may wait up to a second for the robot's Ack; the io threads never wait).
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

#include "pc_server/console/console.hpp"

namespace inspect::server::foxglove {

class ClientOperator {
 public:
  using Configure = std::function<void(Console&)>;
  using Done = std::function<void(bool ok, const std::string& text)>;

  ClientOperator(const std::string& who, RobotRegistry& registry, CommandSink& sink, ControlArbiter& control,
                 const Console::Options& options, const Configure& configure);
  /// Ends the worker (a waiting command is interrupted) and closes the session:
  /// the robots it controlled are free, their teleop set-points cleared.
  ~ClientOperator();
  ClientOperator(const ClientOperator&) = delete;
  ClientOperator& operator=(const ClientOperator&) = delete;

  uint64_t session() const { return session_; }
  const std::string& name() const { return name_; }
  /// Queues `line` (after "select <robot>" when robot is not empty); `done`
  /// runs on the worker with the command's output. False when kMaxQueued calls wait already.
  bool post(const std::string& robot, const std::string& line, Done done);
  /// The robot the session has selected ("" = none yet).
  std::string selected() const;
  static constexpr std::size_t kMaxQueued = 8;

 private:
  struct Job {
    std::string robot, line;
    Done done;
  };
  void run();

  RobotRegistry& registry_;
  CommandSink& sink_;
  ControlArbiter& control_;
  uint64_t session_;
  std::string name_;
  StopFlag stop_;
  std::ostringstream out_;
  std::unique_ptr<Console> console_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  bool ending_ = false;
  std::string selected_;
  std::thread worker_;
};

}  // namespace inspect::server::foxglove
