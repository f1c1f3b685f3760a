#include "pc_server/operator/control_arbiter.hpp"

namespace inspect::server {

uint64_t ControlArbiter::openSession(const std::string& who) {
  std::lock_guard lk(mu_);
  const uint64_t id = next_session_++;
  sessions_[id] = who + " (session " + std::to_string(id) + ")";
  return id;
}

std::vector<std::string> ControlArbiter::closeSession(uint64_t session) {
  std::lock_guard lk(mu_);
  std::vector<std::string> released;
  for (auto it = holders_.begin(); it != holders_.end();) {
    if (it->second.session == session) {
      released.push_back(it->first);
      it = holders_.erase(it);
    } else {
      ++it;
    }
  }
  sessions_.erase(session);
  notes_.erase(session);
  return released;
}

std::string ControlArbiter::sessionName(uint64_t session) const {
  std::lock_guard lk(mu_);
  const auto it = sessions_.find(session);
  return it == sessions_.end() ? "session " + std::to_string(session) : it->second;
}

std::string ControlArbiter::refusal(const std::string& robot, const Holder& h) const {
  return robot + " is controlled by " + h.name + "; this session only observes it (stop and estop still work). "
         "Ask them to 'control release', or 'control take force' to take over (it stops the robot)";
}

ControlArbiter::Decision ControlArbiter::authorizeMotion(const std::string& robot, uint64_t session, int64_t now_ns) {
  std::lock_guard lk(mu_);
  Decision d;
  const auto it = holders_.find(robot);
  if (it == holders_.end()) {
    const auto s = sessions_.find(session);
    holders_[robot] = {session, s == sessions_.end() ? "session " + std::to_string(session) : s->second, now_ns};
    d.allowed = d.taken_now = true;
  } else if (it->second.session == session) {
    d.allowed = true;
  } else {
    d.reason = refusal(robot, it->second);
  }
  return d;
}

ControlArbiter::TakeResult ControlArbiter::take(const std::string& robot, uint64_t session, bool force,
                                                int64_t now_ns) {
  std::lock_guard lk(mu_);
  TakeResult r;
  const auto s = sessions_.find(session);
  const std::string me = s == sessions_.end() ? "session " + std::to_string(session) : s->second;
  const auto it = holders_.find(robot);
  if (it != holders_.end() && it->second.session != session) {
    if (!force) {
      r.reason = robot + " is controlled by " + it->second.name +
                 "; 'control take force' takes over (it stops the robot and tells them)";
      return r;
    }
    r.previous = it->second;
    notes_[it->second.session].push_back("control of " + robot + " taken over by " + me +
                                         " (the robot was stopped); this session now only observes it");
  }
  if (it == holders_.end() || it->second.session != session) holders_[robot] = {session, me, now_ns};
  r.ok = true;
  return r;
}

bool ControlArbiter::release(const std::string& robot, uint64_t session, std::string* reason) {
  std::lock_guard lk(mu_);
  const auto it = holders_.find(robot);
  if (it == holders_.end() || it->second.session != session) {
    if (reason)
      *reason = it == holders_.end() ? robot + " has no controlling session"
                                     : robot + " is controlled by " + it->second.name + ", not this session";
    return false;
  }
  holders_.erase(it);
  return true;
}

std::optional<ControlArbiter::Holder> ControlArbiter::holder(const std::string& robot) const {
  std::lock_guard lk(mu_);
  const auto it = holders_.find(robot);
  if (it == holders_.end()) return std::nullopt;
  return it->second;
}

std::map<std::string, ControlArbiter::Holder> ControlArbiter::holders() const {
  std::lock_guard lk(mu_);
  return holders_;
}

std::vector<std::string> ControlArbiter::takeNotes(uint64_t session) {
  std::lock_guard lk(mu_);
  auto it = notes_.find(session);
  if (it == notes_.end()) return {};
  auto out = std::move(it->second);
  notes_.erase(it);
  return out;
}

}  // namespace inspect::server
