#pragma once
// One controlling operator per robot (docs/console.md, "Sessions and
// control"). Every console is a session; the session holding a robot's
// control is the only one whose motion commands reach it. Others observe:
// they see its status, events and runs, and may always stop or e-stop it.
// Thread-safe: sessions run on their own threads.
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace inspect::server {

class ControlArbiter {
 public:
  struct Holder {
    uint64_t session = 0;
    std::string name;  // "alice (session 2)"
    int64_t since_ns = 0;
  };
  /// What a motion command may do: go ahead (perhaps having just taken a free
  /// robot), or be refused with the reason to print.
  struct Decision {
    bool allowed = false;
    bool taken_now = false;  // the robot was free and this session took it
    std::string reason;      // when refused: who holds it and how to take over
  };

  /// A new session id (> 0) and its display name "<who> (session <n>)".
  uint64_t openSession(const std::string& who);
  /// Releases every robot the session holds; returns them.
  std::vector<std::string> closeSession(uint64_t session);
  std::string sessionName(uint64_t session) const;

  /// Before a motion command: allowed when this session holds the robot, or
  /// when nobody does (the session takes it). Refused when another holds it.
  Decision authorizeMotion(const std::string& robot, uint64_t session, int64_t now_ns);
  /// `control take`: succeeds when free or already held; with `force` also
  /// from another session, which is told (notes) - the caller stops the robot.
  /// Returns the previous holder taken over from, or a refusal reason.
  struct TakeResult {
    bool ok = false;
    std::optional<Holder> previous;  // set when taken over from another session
    std::string reason;
  };
  TakeResult take(const std::string& robot, uint64_t session, bool force, int64_t now_ns);
  /// `control release`: false (with reason) when this session does not hold it.
  bool release(const std::string& robot, uint64_t session, std::string* reason = nullptr);
  std::optional<Holder> holder(const std::string& robot) const;
  /// Every robot with a controller, by robot id.
  std::map<std::string, Holder> holders() const;

  /// Messages for a session from others ("control of robot1 taken over by ..."); drained.
  std::vector<std::string> takeNotes(uint64_t session);

 private:
  std::string refusal(const std::string& robot, const Holder& h) const;
  mutable std::mutex mu_;
  uint64_t next_session_ = 1;
  std::map<uint64_t, std::string> sessions_;
  std::map<std::string, Holder> holders_;
  std::map<uint64_t, std::vector<std::string>> notes_;
};

}  // namespace inspect::server
