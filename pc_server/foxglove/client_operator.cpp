#include "pc_server/foxglove/client_operator.hpp"

#include <chrono>

#include "shared/util/log.hpp"

namespace inspect::server::foxglove {

ClientOperator::ClientOperator(const std::string& who, RobotRegistry& registry, CommandSink& sink,
                               ControlArbiter& control, const Console::Options& options, const Configure& configure)
    : registry_(registry), sink_(sink), control_(control), session_(control.openSession(who)),
      name_(control.sessionName(session_)) {
  Console::Options o = options;
  o.allow_drive = false;      // teleop from a client is its Teleop panel's, with the deadman
  o.feeds_watchdog = false;   // the link's console watchdog is the typed consoles'
  console_ = std::make_unique<Console>(registry_, sink_, out_, stop_, o);
  console_->setSession(&control_, session_);
  console_->eventsFromNow();
  if (configure) configure(*console_);
  worker_ = std::thread([this] { run(); });
}

ClientOperator::~ClientOperator() {
  {
    std::lock_guard lk(mu_);
    ending_ = true;
  }
  stop_.request();
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  console_.reset();
  for (const auto& robot : control_.closeSession(session_)) sink_.clearTeleop(robot);
}

bool ClientOperator::post(const std::string& robot, const std::string& line, Done done) {
  {
    std::lock_guard lk(mu_);
    if (ending_ || jobs_.size() >= kMaxQueued) return false;
    jobs_.push_back({robot, line, std::move(done)});
  }
  cv_.notify_one();
  return true;
}

std::string ClientOperator::selected() const {
  std::lock_guard lk(mu_);
  return selected_;
}

void ClientOperator::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock lk(mu_);
      cv_.wait_for(lk, std::chrono::milliseconds(200), [&] { return ending_ || !jobs_.empty(); });
      if (ending_) break;
      if (jobs_.empty()) {
        lk.unlock();
        (void)console_->background();  // keeps the session's selection and event cursor current
        std::lock_guard lk2(mu_);
        selected_ = console_->selected();
        continue;
      }
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    (void)console_->background();
    out_.str("");
    bool ok = true;
    if (!job.robot.empty()) ok = console_->execute("select " + job.robot, 0);
    if (ok) ok = console_->execute(job.line, 0);
    std::string text = out_.str();
    while (!text.empty() && text.back() == '\n') text.pop_back();
    out_.str("");
    {
      std::lock_guard lk(mu_);
      selected_ = console_->selected();
    }
    if (job.done) job.done(ok, text);
  }
}

}  // namespace inspect::server::foxglove
