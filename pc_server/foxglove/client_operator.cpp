#include "pc_server/foxglove/client_operator.hpp"

#include <boost/asio/post.hpp>

namespace inspect::server::foxglove {

ClientOperator::ClientOperator(const std::string& who, RobotRegistry& registry, CommandSink& sink,
                               ControlArbiter& control, const Console::Options& options, const Configure& configure,
                               ConsolePool& pool)
    : registry_(registry), sink_(sink), control_(control), session_(control.openSession(who)),
      name_(control.sessionName(session_)), strand_(boost::asio::make_strand(pool.executor())) {
  Console::Options o = options;
  o.allow_drive = false;      // teleop from a client is its Teleop panel's, with the deadman
  o.feeds_watchdog = false;   // the link's console watchdog is the typed consoles'
  console_ = std::make_unique<Console>(registry_, sink_, out_, stop_, o);
  console_->setSession(&control_, session_);
  console_->eventsFromNow();
  if (configure) configure(*console_);
}

ClientOperator::~ClientOperator() {
  console_.reset();
  for (const auto& robot : control_.closeSession(session_)) sink_.clearTeleop(robot);
}

bool ClientOperator::post(const std::string& robot, const std::string& line, Done done) {
  if (ending_) return false;
  if (queued_.fetch_add(1) >= kMaxQueued) {
    --queued_;
    return false;
  }
  boost::asio::post(strand_, [self = shared_from_this(), robot, line, done = std::move(done)] {
    --self->queued_;
    if (!self->ending_) self->run(robot, line, done);
  });
  return true;
}

void ClientOperator::end() {
  ending_ = true;
  stop_.request();
}

std::string ClientOperator::selected() const {
  std::lock_guard lk(mu_);
  return selected_;
}

void ClientOperator::run(const std::string& robot, const std::string& line, const Done& done) {
  (void)console_->background();  // the session's selection and event cursor, current
  out_.str("");
  bool ok = true;
  if (!robot.empty()) ok = console_->select(robot);
  if (ok && !line.empty()) ok = console_->execute(line, 0);
  std::string text = out_.str();
  while (!text.empty() && text.back() == '\n') text.pop_back();
  out_.str("");
  {
    std::lock_guard lk(mu_);
    selected_ = console_->selected();
  }
  if (done) done(ok, text);
}

}  // namespace inspect::server::foxglove
