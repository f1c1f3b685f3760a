#pragma once
// A Foxglove client as an operator session (docs/foxglove.md): a session of
// the ControlArbiter like any attached console, and a Console of its own for
// the /console service's lines. The typed calls run on the bridge's io
// threads; a console line may wait (an Ack, `wait`, a report), so lines run
// on a small pool shared by every client (the bridge's ConsolePool), one at a
// time and in order per client (a strand of the pool), never on an io thread
// and never on a thread of their own.
#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>

#include <boost/asio/strand.hpp>
#include <boost/asio/thread_pool.hpp>

#include "pc_server/console/console.hpp"

namespace inspect::server::foxglove {

/// The threads every client's console lines share: at most this many lines
/// run at once; the others wait in their clients' queues.
class ConsolePool {
 public:
  explicit ConsolePool(std::size_t threads) : pool_(threads) {}
  ~ConsolePool() { join(); }
  /// Waits for the lines running and queued (their sessions ended first, they return at once).
  void join() { pool_.join(); }
  boost::asio::thread_pool::executor_type executor() { return pool_.get_executor(); }

 private:
  boost::asio::thread_pool pool_;
};

class ClientOperator : public std::enable_shared_from_this<ClientOperator> {
 public:
  using Configure = std::function<void(Console&)>;
  using Done = std::function<void(bool ok, const std::string& text)>;

  ClientOperator(const std::string& who, RobotRegistry& registry, CommandSink& sink, ControlArbiter& control,
                 const Console::Options& options, const Configure& configure, ConsolePool& pool);
  /// Closes the session: the robots it controlled are free, their teleop set-points cleared.
  ~ClientOperator();
  ClientOperator(const ClientOperator&) = delete;
  ClientOperator& operator=(const ClientOperator&) = delete;

  uint64_t session() const { return session_; }
  const std::string& name() const { return name_; }
  /// Queues `line` (after Console::select(robot) when robot is not empty) on the
  /// pool; `done` runs on a pool thread with the line's output. False when
  /// kMaxQueued lines of this client wait already, or the client has ended.
  bool post(const std::string& robot, const std::string& line, Done done);
  /// The client has gone: a line running is interrupted (its waits return),
  /// queued ones are dropped unanswered. The session closes when the last
  /// line lets go of this object.
  void end();
  /// The robot the session's console has selected ("" = none yet).
  std::string selected() const;
  static constexpr std::size_t kMaxQueued = 8;

 private:
  void run(const std::string& robot, const std::string& line, const Done& done);

  RobotRegistry& registry_;
  CommandSink& sink_;
  ControlArbiter& control_;
  uint64_t session_;
  std::string name_;
  StopFlag stop_;
  std::ostringstream out_;
  std::unique_ptr<Console> console_;
  boost::asio::strand<boost::asio::thread_pool::executor_type> strand_;
  std::atomic<std::size_t> queued_{0};
  std::atomic<bool> ending_{false};
  mutable std::mutex mu_;
  std::string selected_;
};

}  // namespace inspect::server::foxglove
