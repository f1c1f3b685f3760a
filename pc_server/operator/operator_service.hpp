#pragma once
// The operator service: one typed call per action an operator takes on a
// robot, the same for every front end (the console, attached consoles, the
// Foxglove bridge; docs/console.md "Sessions and control"). Each call takes
// the operator's session (a ControlArbiter session) and the robot, checks the
// arguments' ranges, the robot's link and the control arbiter, sends the
// command and returns either the result at once (refused before anything was
// sent) or a PendingCall that settles on the robot's Ack or its deadline.
//
// It never waits and holds no thread: a caller waits its own way (the console
// on its clock and the registry's Ack signal; the bridge on a timer of its io
// context) and asks settle(pending, now) until it has the result. Time is
// passed in (monotonic ns, the registry's base), so tests run it on a manual
// clock. Thread-safe as its parts are (registry, sink, arbiter).
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "inspect_robot/v1/link.pb.h"
#include "pc_server/link/command_sink.hpp"
#include "pc_server/link/robot_registry.hpp"
#include "pc_server/operator/control_arbiter.hpp"
#include "pc_server/operator/route_file.hpp"

namespace inspect::server {

class Recorder;
namespace scene {
class SiteMaps;
}

/// What became of a call.
enum class CallOutcome {
  kAccepted,   // the robot took it (a run: completion comes later, as an event and Ack)
  kCompleted,  // the robot finished it already
  kInvalid,    // an argument out of range, no robot named, the robot not connected: nothing sent
  kRefused,    // another session controls the robot: nothing sent
  kRejected,   // the robot answered REJECTED or FAILED (ack_status says which)
  kTimedOut,   // no Ack before the deadline
};
const char* callOutcomeName(CallOutcome o);

struct CallResult {
  CallOutcome outcome = CallOutcome::kInvalid;
  std::string action;          // "goto", "stop", "video res" ...
  std::string robot;           // "" when none could be named
  uint64_t command_id = 0;     // 0 when nothing was sent
  v1::Ack::Status ack_status = v1::Ack::STATUS_UNSPECIFIED;
  v1::Ack ack;                 // the robot's answer (its reason, gains version) when one came
  std::string reason;          // why not: the range, the holder and how to take over, the robot's reason
  double ack_timeout_s = 0.0;  // kTimedOut: how long it waited
  std::string control_note;    // "robot1: control taken by alice (session 2)" when this call took a free robot

  bool ok() const { return outcome == CallOutcome::kAccepted || outcome == CallOutcome::kCompleted; }
  /// The operator's line: "robot1: goto accepted", "goto: no robot selected",
  /// "robot1: goto refused: robot1 is controlled by ...", "robot1: stop: no ack within 1 s".
  std::string text() const;
};

/// A command sent, its Ack not yet in.
struct PendingCall {
  std::string action;
  std::string robot;
  uint64_t command_id = 0;
  int64_t deadline_ns = 0;
  std::string control_note;
  bool forget_run_map = false;  // inspect: the run's pending map is forgotten if the robot does not take it
};

/// A call's first answer: done at once, or pending on the robot.
using Issued = std::variant<CallResult, PendingCall>;

/// `track`'s path (docs/console.md): a circle of radius_m (negative turns
/// right) for laps, or a straight line of length_m; controller "" = the robot's.
struct TrackRequest {
  enum class Shape { kCircle, kLine } shape = Shape::kCircle;
  double size_m = 1.0;  // radius or length
  double speed_m_s = 0.5;
  double laps = 1.0;
  std::string controller;
};

/// `ptz`: home, or pan/tilt in degrees.
struct PtzRequest {
  bool home = false;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
};

/// `video`: exactly one of the settings.
struct VideoRequest {
  enum class What { kOn, kOff, kKeyframe, kRes, kFps, kBitrate } what = What::kOn;
  long long width = 0, height = 0;  // kRes
  double fps = 0.0;                 // kFps
  long long bitrate_kbps = 0;       // kBitrate
  v1::CameraHead head = v1::PTZ_HEAD;  // which head's stream
};

class OperatorService {
 public:
  struct Options {
    double ack_timeout_s = 1.0;  // a command's Ack is waited for this long
    double max_v_m_s = 1.0;      // teleop limits
    double max_w_rad_s = 2.0;
  };
  /// `control` null: no sessions (every call may move every robot).
  OperatorService(RobotRegistry& registry, CommandSink& sink, ControlArbiter* control, Options options);

  // Always allowed (any session, controlling or not): the robot stops.
  Issued stop(uint64_t session, const std::string& robot, int64_t now_ns);
  Issued estop(uint64_t session, const std::string& robot, int64_t now_ns);
  // Need the robot's control (taken when free).
  Issued resume(uint64_t session, const std::string& robot, int64_t now_ns);
  /// A goal outside the robot's site map (the box of its walls, in the
  /// robot's odometry frame) is refused with the map's bounds, unless forced.
  Issued goTo(uint64_t session, const std::string& robot, double x_m, double y_m, std::optional<double> speed_m_s,
              int64_t now_ns, bool force = false);
  Issued track(uint64_t session, const std::string& robot, const TrackRequest& t, int64_t now_ns);
  Issued ptz(uint64_t session, const std::string& robot, const PtzRequest& p, int64_t now_ns);
  /// The camera stream's settings (no control needed: they move nothing).
  Issued video(uint64_t session, const std::string& robot, const VideoRequest& v, int64_t now_ns);
  /// A teleop set-point, re-sent by the robot's session; with lease_s > 0 it
  /// lapses to zero that long after this call (operator silence), 0 = held
  /// until stop. Refused (and the set-point cleared) on REJECTED; a caller
  /// that gets kTimedOut clears it too (clearTeleop).
  Issued teleop(uint64_t session, const std::string& robot, double v_m_s, double w_rad_s, double lease_s,
                int64_t now_ns);
  /// Any other command (a route's GoTo or wheel test, gains, inspection):
  /// `action` names it; control is needed unless it is a stop, an e-stop or video.
  Issued send(uint64_t session, const std::string& robot, const std::string& action, v1::Command cmd,
              int64_t now_ns);
  void clearTeleop(const std::string& robot) { sink_.clearTeleop(robot); }

  /// Whether `session` may move `robot` now (taking it when free): nullopt
  /// when it may (note: "robot1: control taken by ..." when it took it), the
  /// kRefused result otherwise. For front ends that move a robot by other
  /// means (the keyboard teleop); the calls above check it themselves.
  std::optional<CallResult> authorize(uint64_t session, const std::string& robot, const std::string& action,
                                      int64_t now_ns, std::string* note = nullptr);

  /// `control take [force]`: a forced take-over stops the robot (the new
  /// operator starts from standstill). kAccepted with reason = what happened.
  CallResult takeControl(uint64_t session, const std::string& robot, bool force, int64_t now_ns);
  CallResult releaseControl(uint64_t session, const std::string& robot);

  /// Where the run calls record and draw: the recorder (null: the server
  /// records nothing) and the site maps of the live view (null: none). Set
  /// before the first call.
  void setRunContext(Recorder* recorder, scene::SiteMaps* site_maps);
  Recorder* recorder() const { return recorder_; }

  /// `route`: a route's points (GoTo) or its wheel test; the route's site
  /// map is drawn for the robot once the command is sent. Needs control.
  /// `summary` (when given) gets the operator's line about the route
  /// (routeSummary), to print before the result.
  Issued route(uint64_t session, const std::string& robot, const Route& r, int64_t now_ns,
               std::string* summary = nullptr);
  /// `inspect`: a recorded gas inspection round (docs/gas.md): the route with
  /// the gas reaction and dwells, its map attached to the run the robot's
  /// Ack starts (forgotten again when the robot does not take it). speed_m_s
  /// overrides the route's, within (0, kMaxCommandSpeed_m_s]. Needs control.
  /// `summary` as for route(), at the speed it runs (empty when the speed or route is refused).
  Issued inspect(uint64_t session, const std::string& robot, Route r, std::optional<double> speed_m_s,
                 int64_t now_ns, std::string* summary = nullptr);
  /// Renews the lease of `session`'s leased teleop set-point on `robot`
  /// (the operator is still there), only while that session holds the robot.
  void renewTeleop(uint64_t session, const std::string& robot, double lease_s);
  /// `record start [name]` / `record stop`: a run of the robot's messages
  /// (no control needed: recording moves nothing). kCompleted with reason
  /// "recording run <id>" / "run <id> stopped"; kInvalid when the server
  /// records nothing, the robot is (not) recording, or the run cannot start.
  CallResult recordStart(uint64_t session, const std::string& robot, const std::string& name);
  CallResult recordStop(uint64_t session, const std::string& robot);

  /// `ack <number>|all`: the operator acknowledges gas alarms (number
  /// nullopt = every unacknowledged one), each noted in its robot's run.
  /// Any session may (acknowledging moves nothing). The alarms acknowledged
  /// and the line for each ("alarm #3 (H2S HIGH) acknowledged by the
  /// operator"), or the reason nothing was ("no alarm #9 (alarms lists them)").
  struct AlarmAcks {
    std::vector<std::pair<AlarmRecord, std::string>> acked;
    std::string error;
  };
  AlarmAcks acknowledgeAlarms(uint64_t session, std::optional<int> number, int64_t now_ns);

  /// The result once the robot's Ack is in or the deadline passed; nullopt meanwhile.
  std::optional<CallResult> settle(const PendingCall& p, int64_t now_ns) const;
  /// Moves with every Ack: what a waiting caller may sleep on between settle() calls.
  WakeSignal& ackSignal() { return registry_.ackSignal(); }

  const Options& options() const { return options_; }
  RobotRegistry& registry() { return registry_; }
  ControlArbiter* control() const { return control_; }

 private:
  /// send() with a teleop set-point's lease (teleop commands go to CommandSink::setTeleop).
  Issued dispatch(uint64_t session, const std::string& robot, const std::string& action, v1::Command cmd,
                  double lease_s, int64_t now_ns);
  /// Why (x, y) in the robot's odometry frame is outside its site map; nullopt when inside or no map is known.
  std::optional<std::string> outsideSiteMap(const std::string& robot, double x_m, double y_m) const;
  /// The robot when named and connected; otherwise the kInvalid result.
  std::optional<CallResult> checkConnected(const std::string& action, const std::string& robot, int64_t now_ns) const;
  static CallResult invalid(const std::string& action, const std::string& robot, std::string reason);

  RobotRegistry& registry_;
  CommandSink& sink_;
  ControlArbiter* control_;
  Options options_;
  Recorder* recorder_ = nullptr;
  scene::SiteMaps* site_maps_ = nullptr;
};

}  // namespace inspect::server
