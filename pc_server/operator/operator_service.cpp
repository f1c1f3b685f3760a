#include "pc_server/operator/operator_service.hpp"

#include <algorithm>
#include <cmath>

#include <cmath>

#include "pc_server/operator/command_limits.hpp"
#include "pc_server/recording/recorder.hpp"
#include "pc_server/scene/site_maps.hpp"
#include "shared/util/number_text.hpp"

namespace inspect::server {

using util::fmtShort;

const char* callOutcomeName(CallOutcome o) {
  switch (o) {
    case CallOutcome::kAccepted: return "accepted";
    case CallOutcome::kCompleted: return "completed";
    case CallOutcome::kInvalid: return "invalid";
    case CallOutcome::kRefused: return "refused";
    case CallOutcome::kRejected: return "rejected";
    case CallOutcome::kTimedOut: return "timed out";
  }
  return "?";
}

std::string CallResult::text() const {
  switch (outcome) {
    case CallOutcome::kAccepted:
    case CallOutcome::kCompleted:
      return robot + ": " + action + " " + callOutcomeName(outcome) + (reason.empty() ? "" : " (" + reason + ")");
    case CallOutcome::kInvalid: return action + ": " + reason;
    case CallOutcome::kRefused: return robot + ": " + action + " refused: " + reason;
    case CallOutcome::kRejected:
      return robot + ": " + action + (ack_status == v1::Ack::FAILED ? " failed: " : " rejected: ") + reason;
    case CallOutcome::kTimedOut: return robot + ": " + action + ": no ack within " + fmtShort(ack_timeout_s) + " s";
  }
  return action + ": ?";
}

OperatorService::OperatorService(RobotRegistry& registry, CommandSink& sink, ControlArbiter* control, Options options)
    : registry_(registry), sink_(sink), control_(control), options_(options) {}

CallResult OperatorService::invalid(const std::string& action, const std::string& robot, std::string reason) {
  CallResult r;
  r.outcome = CallOutcome::kInvalid;
  r.action = action;
  r.robot = robot;
  r.reason = std::move(reason);
  return r;
}

std::optional<CallResult> OperatorService::checkConnected(const std::string& action, const std::string& robot,
                                                          int64_t now_ns) const {
  if (robot.empty()) return invalid(action, robot, "no robot selected");
  const auto snap = registry_.snapshot(robot, now_ns);
  if (!snap || !snap->connected) return invalid(action, robot, robot + " is not connected");
  return std::nullopt;
}

Issued OperatorService::send(uint64_t session, const std::string& robot, const std::string& action, v1::Command cmd,
                             int64_t now_ns) {
  return dispatch(session, robot, action, std::move(cmd), 0.0, now_ns);
}

Issued OperatorService::dispatch(uint64_t session, const std::string& robot, const std::string& action,
                                 v1::Command cmd, double lease_s, int64_t now_ns) {
  if (auto bad = checkConnected(action, robot, now_ns)) return *bad;
  // Everything but stop, e-stop and the camera stream's settings moves the robot or its mount.
  const bool motion = !cmd.has_stop() && !cmd.has_estop() && !cmd.has_video();
  PendingCall p{action, robot, 0, 0, ""};
  if (motion)
    if (auto refused = authorize(session, robot, action, now_ns, &p.control_note)) return *refused;
  const bool teleop = cmd.has_teleop();
  p.command_id = teleop ? sink_.setTeleop(robot, cmd.teleop().v_m_s(), cmd.teleop().w_rad_s(), lease_s)
                        : sink_.sendCommand(robot, std::move(cmd));
  if (p.command_id == 0) return invalid(action, robot, robot + " is not connected");
  p.deadline_ns = now_ns + std::llround(options_.ack_timeout_s * 1e9);
  return p;
}

Issued OperatorService::stop(uint64_t session, const std::string& robot, int64_t now_ns) {
  v1::Command c;
  c.mutable_stop();
  return send(session, robot, "stop", std::move(c), now_ns);
}

Issued OperatorService::estop(uint64_t session, const std::string& robot, int64_t now_ns) {
  v1::Command c;
  c.mutable_estop();
  return send(session, robot, "estop", std::move(c), now_ns);
}

Issued OperatorService::resume(uint64_t session, const std::string& robot, int64_t now_ns) {
  v1::Command c;
  c.mutable_resume();
  return send(session, robot, "resume", std::move(c), now_ns);
}

std::optional<std::string> OperatorService::outsideSiteMap(const std::string& robot, double x_m, double y_m) const {
  if (!site_maps_) return std::nullopt;
  const auto entry = site_maps_->get(robot);
  if (!entry.map || entry.map->walls.empty()) return std::nullopt;
  const scene::SiteMap& m = *entry.map;
  // The walls in the robot's odometry frame: its origin and x axis are the
  // map's start pose.
  const double c = std::cos(m.start_theta_rad), s = std::sin(m.start_theta_rad);
  double lo_x = INFINITY, lo_y = INFINITY, hi_x = -INFINITY, hi_y = -INFINITY;
  for (const auto& w : m.walls)
    for (const auto& p : {w.a, w.b}) {
      const double dx = p.x - m.start_x_m, dy = p.y - m.start_y_m;
      const double ox = c * dx + s * dy, oy = -s * dx + c * dy;
      lo_x = std::min(lo_x, ox);
      hi_x = std::max(hi_x, ox);
      lo_y = std::min(lo_y, oy);
      hi_y = std::max(hi_y, oy);
    }
  if (x_m >= lo_x && x_m <= hi_x && y_m >= lo_y && y_m <= hi_y) return std::nullopt;
  return "(" + fmtShort(x_m) + ", " + fmtShort(y_m) + ") is outside the site map " + m.name + ": its walls span x [" +
         fmtShort(lo_x) + ", " + fmtShort(hi_x) + "], y [" + fmtShort(lo_y) + ", " + fmtShort(hi_y) +
         "] m in the robot's odometry frame; `goto " + fmtShort(x_m) + " " + fmtShort(y_m) +
         " force` sends it anyway";
}

Issued OperatorService::goTo(uint64_t session, const std::string& robot, double x_m, double y_m,
                             std::optional<double> speed_m_s, int64_t now_ns, bool force) {
  if (!(std::fabs(x_m) <= 1000) || !(std::fabs(y_m) <= 1000))
    return invalid("goto", robot, "x and y must be in [-1000, 1000] m");
  if (speed_m_s && (!(*speed_m_s > 0) || *speed_m_s > kMaxCommandSpeed_m_s))
    return invalid("goto", robot,
                   "speed " + fmtShort(*speed_m_s) + " m/s is outside (0, " + fmtShort(kMaxCommandSpeed_m_s) + "]");
  if (!force)
    if (auto why = outsideSiteMap(robot, x_m, y_m)) return invalid("goto", robot, *why);
  v1::Command c;
  auto* g = c.mutable_go_to();
  auto* p = g->add_points();
  p->set_x_m(x_m);
  p->set_y_m(y_m);
  if (speed_m_s) g->set_speed_m_s(*speed_m_s);
  return send(session, robot, "goto", std::move(c), now_ns);
}

Issued OperatorService::track(uint64_t session, const std::string& robot, const TrackRequest& t, int64_t now_ns) {
  if (!(t.speed_m_s > 0) || t.speed_m_s > kMaxCommandSpeed_m_s)
    return invalid("track", robot,
                   "speed " + fmtShort(t.speed_m_s) + " m/s is outside (0, " + fmtShort(kMaxCommandSpeed_m_s) + "]");
  if (!t.controller.empty() && t.controller != "fuzzy_pid" && t.controller != "pid" && t.controller != "direct")
    return invalid("track", robot, "unknown controller '" + t.controller + "' (fuzzy_pid, pid, direct)");
  v1::Command c;
  auto* k = c.mutable_track();
  k->set_controller(t.controller);
  if (t.shape == TrackRequest::Shape::kCircle) {
    if (!(std::fabs(t.size_m) >= 0.1) || std::fabs(t.size_m) > 100)
      return invalid("track", robot, "radius must be 0.1 to 100 m (negative turns right)");
    if (!(t.laps > 0) || t.laps > 100) return invalid("track", robot, "laps must be in (0, 100]");
    k->mutable_circle()->set_radius_m(t.size_m);
    k->mutable_circle()->set_speed_m_s(t.speed_m_s);
    k->mutable_circle()->set_laps(t.laps);
  } else {
    if (!(t.size_m > 0) || t.size_m > 1000) return invalid("track", robot, "length must be in (0, 1000] m");
    k->mutable_line()->set_length_m(t.size_m);
    k->mutable_line()->set_speed_m_s(t.speed_m_s);
  }
  return send(session, robot, "track", std::move(c), now_ns);
}

Issued OperatorService::ptz(uint64_t session, const std::string& robot, const PtzRequest& r, int64_t now_ns) {
  v1::Command c;
  auto* p = c.mutable_ptz();
  if (r.home) {
    p->set_home(true);
  } else {
    if (!(std::fabs(r.pan_deg) <= 180) || !(std::fabs(r.tilt_deg) <= 90))
      return invalid("ptz", robot, "pan must be within [-180, 180] and tilt within [-90, 90] degrees");
    p->set_pan_rad(r.pan_deg * M_PI / 180.0);
    p->set_tilt_rad(r.tilt_deg * M_PI / 180.0);
  }
  return send(session, robot, "ptz", std::move(c), now_ns);
}

Issued OperatorService::video(uint64_t session, const std::string& robot, const VideoRequest& r, int64_t now_ns) {
  using W = VideoRequest::What;
  v1::Command c;
  auto* v = c.mutable_video();
  v->set_head(r.head);
  if (r.head == v1::WIDE_HEAD) {
    // A robot from before the wide head's stream would take the command for the PTZ head's.
    const auto snap = registry_.snapshot(robot, now_ns);
    if (snap && snap->connected && snap->has_telemetry && !snap->telemetry.has_wide_video())
      return invalid("video", robot,
                     robot + " does not stream a wide head (its config's wide_head.stream, robot_client --wide-stream)");
  }
  std::string what;
  switch (r.what) {
    case W::kOn:
    case W::kOff:
      v->set_enabled(r.what == W::kOn);
      what = r.what == W::kOn ? "on" : "off";
      break;
    case W::kKeyframe:
      v->set_keyframe(true);
      what = "keyframe";
      break;
    case W::kRes:
      if (r.width < kVideoMinSide || r.height < kVideoMinSide || r.width > kVideoMaxSide ||
          r.height > kVideoMaxSide || r.width % 2 || r.height % 2)
        return invalid("video", robot,
                       "res '" + std::to_string(r.width) + "x" + std::to_string(r.height) + "': want " + kVideoSizeWant);
      v->set_width(static_cast<uint32_t>(r.width));
      v->set_height(static_cast<uint32_t>(r.height));
      what = "res";
      break;
    case W::kFps:
      if (!(r.fps >= kVideoMinFps && r.fps <= kVideoMaxFps))
        return invalid("video", robot, "fps '" + fmtShort(r.fps) + "': want " + kVideoFpsWant);
      v->set_fps(r.fps);
      what = "fps";
      break;
    case W::kBitrate:
      if (r.bitrate_kbps < kVideoMinBitrate_kbps || r.bitrate_kbps > kVideoMaxBitrate_kbps)
        return invalid("video", robot, "bitrate '" + std::to_string(r.bitrate_kbps) + "': want " + kVideoBitrateWant);
      v->set_bitrate_kbps(static_cast<uint32_t>(r.bitrate_kbps));
      what = "bitrate";
      break;
  }
  return send(session, robot, std::string(r.head == v1::WIDE_HEAD ? "video wide " : "video ") + what, std::move(c), now_ns);
}

Issued OperatorService::teleop(uint64_t session, const std::string& robot, double v_m_s, double w_rad_s,
                               double lease_s, int64_t now_ns) {
  if (!std::isfinite(v_m_s) || std::fabs(v_m_s) > options_.max_v_m_s)
    return invalid("drive", robot,
                   "v " + fmtShort(v_m_s) + " m/s is outside [-" + fmtShort(options_.max_v_m_s) + ", " +
                       fmtShort(options_.max_v_m_s) + "]");
  if (!std::isfinite(w_rad_s) || std::fabs(w_rad_s) > options_.max_w_rad_s)
    return invalid("drive", robot,
                   "w " + fmtShort(w_rad_s) + " rad/s is outside [-" + fmtShort(options_.max_w_rad_s) + ", " +
                       fmtShort(options_.max_w_rad_s) + "]");
  v1::Command c;
  c.mutable_teleop()->set_v_m_s(v_m_s);
  c.mutable_teleop()->set_w_rad_s(w_rad_s);
  return dispatch(session, robot, "drive", std::move(c), lease_s, now_ns);
}

std::optional<CallResult> OperatorService::authorize(uint64_t session, const std::string& robot,
                                                    const std::string& action, int64_t now_ns, std::string* note) {
  if (!control_) return std::nullopt;
  const auto d = control_->authorizeMotion(robot, session, now_ns);
  if (d.allowed) {
    if (d.taken_now && note) *note = robot + ": control taken by " + control_->sessionName(session);
    return std::nullopt;
  }
  CallResult r;
  r.outcome = CallOutcome::kRefused;
  r.action = action;
  r.robot = robot;
  r.reason = d.reason;
  return r;
}

CallResult OperatorService::takeControl(uint64_t session, const std::string& robot, bool force, int64_t now_ns) {
  if (!control_) return invalid("control", robot, "this console has no sessions (no control arbiter)");
  if (robot.empty()) return invalid("control", robot, "no robot selected");
  const auto t = control_->take(robot, session, force, now_ns);
  if (!t.ok) return invalid("control", robot, t.reason);
  CallResult r;
  r.outcome = CallOutcome::kCompleted;
  r.action = "control take";
  r.robot = robot;
  if (t.previous) {
    // The new operator starts from standstill: nothing of the old one's commands goes on.
    sink_.clearTeleop(robot);
    v1::Command stop;
    stop.mutable_stop();
    r.command_id = sink_.sendCommand(robot, std::move(stop));
    r.reason = "control taken over from " + t.previous->name + " (robot stopped)";
  } else {
    r.reason = "controlled by " + control_->sessionName(session);
  }
  return r;
}

CallResult OperatorService::releaseControl(uint64_t session, const std::string& robot) {
  if (!control_) return invalid("control", robot, "this console has no sessions (no control arbiter)");
  if (robot.empty()) return invalid("control", robot, "no robot selected");
  std::string why;
  if (!control_->release(robot, session, &why)) return invalid("control", robot, why);
  sink_.clearTeleop(robot);
  CallResult r;
  r.outcome = CallOutcome::kCompleted;
  r.action = "control release";
  r.robot = robot;
  r.reason = "control released; the robot is free";
  return r;
}

void OperatorService::renewTeleop(uint64_t session, const std::string& robot, double lease_s) {
  if (robot.empty() || !(lease_s > 0)) return;
  if (control_) {
    const auto h = control_->holder(robot);
    if (!h || h->session != session) return;  // taken over or released: not this session's to keep moving
  }
  sink_.renewTeleop(robot, lease_s);
}

void OperatorService::setRunContext(Recorder* recorder, scene::SiteMaps* site_maps) {
  recorder_ = recorder;
  site_maps_ = site_maps;
}

Issued OperatorService::route(uint64_t session, const std::string& robot, const Route& r, int64_t now_ns,
                              std::string* summary) {
  if (summary) *summary = routeSummary(r, false);
  v1::Command c;
  if (r.isWheelTest())
    *c.mutable_wheel_test() = wheelTestOf(r);
  else
    *c.mutable_go_to() = goToOf(r);
  Issued issued = send(session, robot, "route", std::move(c), now_ns);
  if (site_maps_ && !r.map.empty() && std::holds_alternative<PendingCall>(issued)) site_maps_->set(robot, r.map);
  return issued;
}

Issued OperatorService::inspect(uint64_t session, const std::string& robot, Route r, std::optional<double> speed_m_s,
                                int64_t now_ns, std::string* summary) {
  if (speed_m_s) {
    if (!commandSpeedOk(*speed_m_s))
      return invalid("inspect", robot,
                     "speed_m_s '" + fmtShort(*speed_m_s) + "' must be a number in (0, " +
                         fmtShort(kMaxCommandSpeed_m_s) + "] m/s");
    r.speed_m_s = *speed_m_s;
  }
  if (r.isWheelTest()) return invalid("inspect", robot, "'" + r.name + "' is a wheel test, not an inspection route");
  if (summary) *summary = routeSummary(r, true);
  if (auto bad = checkConnected("inspect", robot, now_ns)) return *bad;
  // The map goes to the run before the command: the robot's Ack starts the run.
  const bool run_map = recorder_ && !r.map.empty();
  if (run_map) recorder_->setRunMap(robot, r.map);
  v1::Command c;
  *c.mutable_go_to() = goToOf(r, true);
  Issued issued = send(session, robot, "inspect", std::move(c), now_ns);
  if (auto* p = std::get_if<PendingCall>(&issued)) {
    p->forget_run_map = run_map;
    if (site_maps_ && !r.map.empty()) site_maps_->set(robot, r.map);
  } else if (run_map) {
    recorder_->setRunMap(robot, "");  // nothing sent: no run to attach the map to
  }
  return issued;
}

CallResult OperatorService::recordStart(uint64_t, const std::string& robot, const std::string& name) {
  if (!recorder_) return invalid("record", robot, "the server records nothing (recording.enabled: false or --no-record)");
  if (robot.empty()) return invalid("record", robot, "no robot selected");
  try {
    CallResult r;
    r.outcome = CallOutcome::kCompleted;
    r.action = "record start";
    r.robot = robot;
    r.reason = "recording run " + recorder_->start(robot, name);
    return r;
  } catch (const std::exception& e) {
    return invalid("record", robot, e.what());
  }
}

CallResult OperatorService::recordStop(uint64_t, const std::string& robot) {
  if (!recorder_) return invalid("record", robot, "the server records nothing (recording.enabled: false or --no-record)");
  if (robot.empty()) return invalid("record", robot, "no robot selected");
  const auto id = recorder_->stop(robot, "stopped");
  if (!id) return invalid("record", robot, robot + " is not recording");
  CallResult r;
  r.outcome = CallOutcome::kCompleted;
  r.action = "record stop";
  r.robot = robot;
  r.reason = "run " + *id + " stopped";
  return r;
}

OperatorService::AlarmAcks OperatorService::acknowledgeAlarms(uint64_t, std::optional<int> number, int64_t now_ns) {
  AlarmAcks out;
  std::vector<AlarmRecord> done;
  if (!number) {
    done = registry_.ackAllAlarms(now_ns);
    if (done.empty()) out.error = "nothing to acknowledge";
  } else if (const auto r = registry_.ackAlarm(*number, now_ns)) {
    done.push_back(*r);
  } else {
    out.error = "no alarm #" + std::to_string(*number) + " (alarms lists them)";
  }
  for (const auto& r : done) {
    std::string text = "alarm #" + std::to_string(r.number) + " (" + r.alarm.channel_name() + " " +
                       v1::GasAlarm::Level_Name(r.alarm.level()) + ") acknowledged by the operator";
    if (recorder_) recorder_->noteAlarmAck(r.robot_id, r.alarm, text);
    out.acked.emplace_back(r, std::move(text));
  }
  return out;
}

std::optional<CallResult> OperatorService::settle(const PendingCall& p, int64_t now_ns) const {
  CallResult r;
  r.action = p.action;
  r.robot = p.robot;
  r.command_id = p.command_id;
  r.control_note = p.control_note;
  const auto ack = registry_.ack(p.robot, p.command_id);
  if (!ack) {
    if (now_ns < p.deadline_ns) return std::nullopt;
    r.outcome = CallOutcome::kTimedOut;
    r.ack_timeout_s = options_.ack_timeout_s;
    if (p.forget_run_map && recorder_) recorder_->setRunMap(p.robot, "");
    return r;
  }
  r.ack_status = ack->status();
  r.ack = *ack;
  switch (ack->status()) {
    case v1::Ack::ACCEPTED: r.outcome = CallOutcome::kAccepted; break;
    case v1::Ack::COMPLETED: r.outcome = CallOutcome::kCompleted; break;
    case v1::Ack::FAILED:
    case v1::Ack::REJECTED:
      r.outcome = CallOutcome::kRejected;
      r.reason = ack->reason();
      break;
    default:
      r.outcome = CallOutcome::kRejected;
      r.reason = "an Ack with an unknown status " + std::to_string(ack->status());
      break;
  }
  if (p.forget_run_map && !r.ok() && recorder_) recorder_->setRunMap(p.robot, "");
  return r;
}

}  // namespace inspect::server
