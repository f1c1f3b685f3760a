#include "shared/robot/robot_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace inspect::robot {
namespace {

std::string faultName(uint32_t f) {
  switch (f) {
    case v1::FAULT_LINK_LOST: return "link lost";
    case v1::FAULT_SENSOR_STALE: return "sensor frames stale";
    case v1::FAULT_SERIAL_DOWN: return "serial device down";
    case v1::FAULT_MCU: return "MCU fault";
    case v1::FAULT_COMMAND_STALE: return "teleop set-point stale";
    default: return "fault";
  }
}

int16_t toMrad(double rad_s) {
  const double v = std::clamp(std::round(rad_s * 1000.0), -32767.0, 32767.0);
  return static_cast<int16_t>(v);
}

// Moves `cur` toward `target` by at most `step`.
double slew(double cur, double target, double step) {
  if (target > cur + step) return cur + step;
  if (target < cur - step) return cur - step;
  return target;
}

// The control config with the robot's geometry and limits applied.
config::ControlConfig applied(config::ControlConfig control, const config::RobotConfig& robot) {
  config::applyRobot(control, robot);
  return control;
}

}  // namespace

RobotCore::RobotCore(const config::RobotConfig& robot, const SafetyParams& safety,
                     const config::ControlConfig& control, std::shared_ptr<control::FuzzyGainScheduler> scheduler)
    : robot_(robot),
      safety_(safety),
      control_(applied(control, robot)),
      gains_(control_, std::move(scheduler)),
      gas_(robot.gas) {}

std::vector<v1::Ptz> RobotCore::takePtz() {
  std::vector<v1::Ptz> out;
  out.swap(route_.ptz());
  return out;
}

std::vector<v1::Ack> RobotCore::takeAcks() {
  std::vector<v1::Ack> out;
  out.swap(acks_);
  return out;
}

void RobotCore::onGasTransitions(double now_s) {
  for (const auto& t : gas_.transitions()) {
    events_.push(gas_.eventOf(t, now_s, estimate_.pose()));
    // The reaction to a HIGH alarm on a route (docs/gas.md).
    if (t.level == gas::AlarmLevel::High && t.active && mode_ == v1::NAVIGATING && route_.active())
      route_.onGasHigh(gas_.channelName(t.channel) + " HIGH alarm", safety_.gas_reaction, events_);
  }
  gas_.clearTransitions();
}

void RobotCore::applyPendingGains() {
  auto in_force = gains_.applyPending(track_.active());
  if (!in_force) return;
  track_.setGains(gains_.gains(), in_force->new_scheduler);
  events_.push(std::move(in_force->event));
}

v1::Ack RobotCore::startTrack(const v1::Command& cmd) {
  applyPendingGains();
  std::string what;
  if (const std::string why = track_.start(cmd.track(), cmd.id(), estimate_.pose(), control_, gains_.gains(),
                                           gains_.scheduler(), robot_.limits, what);
      !why.empty())
    return ackOf(cmd.id(), v1::Ack::REJECTED, why);
  clearSetpoint();
  setMode(v1::TRACKING, "tracking " + what);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

v1::Ack RobotCore::startWheelTest(const v1::Command& cmd) {
  std::string why;
  auto profile = WheelTestRunner::profileOf(cmd.wheel_test(), robot_, why);
  if (!profile) return ackOf(cmd.id(), v1::Ack::REJECTED, why);
  endAutonomy();
  const std::string what = wheel_test_.start(std::move(profile), cmd.wheel_test(), cmd.id(), estimate_.pose());
  clearSetpoint();
  setMode(v1::WHEEL_TEST, what);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

v1::Ack RobotCore::startGoTo(const v1::Command& cmd) {
  RouteRunner::Plan plan;
  if (const std::string why = RouteRunner::plan(cmd.go_to(), robot_, plan); !why.empty())
    return ackOf(cmd.id(), v1::Ack::REJECTED, why);
  const bool was_navigating = mode_ == v1::NAVIGATING;
  endAutonomy();
  const std::string what = route_.begin(std::move(plan), cmd.go_to(), cmd.id(), estimate_.pose());
  clearSetpoint();
  if (was_navigating) events_.push(v1::Event::INFO, "navigating " + what);
  setMode(v1::NAVIGATING, "navigating " + what);
  return ackOf(cmd.id(), v1::Ack::ACCEPTED);
}

std::string RobotCore::autonomyRefusal() const {
  if (mode_ == v1::ESTOP) return "e-stop latched: resume first";
  if (mode_ == v1::FAILSAFE) return "failsafe latched (" + latch_reason_ + "): resume first";
  if (faults_ & v1::FAULT_SENSOR_STALE) return "sensor frames stale";
  if (faults_ & v1::FAULT_SERIAL_DOWN) return "serial device down";
  if (!estimate_.haveFrame()) return "no sensor frame yet: the pose is unknown";
  return "";
}

void RobotCore::endAutonomy() {
  track_.end();
  wheel_test_.end();
  route_.end();
}

void RobotCore::finishRun(RunEnd end) {
  acks_.push_back(std::move(end.ack));
  endAutonomy();
  cmd_wheels_ = {};
  setMode(v1::IDLE, end.why);
}

void RobotCore::setMode(v1::Mode m, const std::string& why) {
  if (m == mode_) return;
  mode_ = m;
  events_.push(v1::Event::MODE_CHANGE, std::string(v1::Mode_Name(m)) + ": " + why);
}

void RobotCore::raise(uint32_t fault, const std::string& why) {
  if (faults_ & fault) return;
  faults_ |= fault;
  events_.push(v1::Event::FAULT_RAISED, faultName(fault) + (why.empty() ? "" : ": " + why));
}

void RobotCore::clear(uint32_t fault, const std::string& why) {
  if (!(faults_ & fault)) return;
  faults_ &= ~fault;
  events_.push(v1::Event::FAULT_CLEARED, faultName(fault) + (why.empty() ? "" : ": " + why));
}

void RobotCore::latchFailsafe(const std::string& why) {
  clearSetpoint();
  endAutonomy();
  if (latched()) return;
  latch_reason_ = why;
  setMode(v1::FAILSAFE, why + "; needs resume");
}

void RobotCore::onLinkUp(double now_s) {
  link_.up = true;
  link_.last_activity_s = now_s;
  clear(v1::FAULT_LINK_LOST, "link restored");
}

void RobotCore::onLinkDown(double /*now_s*/, const std::string& why) {
  link_.up = false;
  raise(v1::FAULT_LINK_LOST, why);
  if (movingAtLinkLoss()) latchFailsafe("link lost");
  clearSetpoint();
}

void RobotCore::onLinkActivity(double now_s) {
  // A message after a silence that no timer saw in time (this process was
  // stalled, or its loop was late) still ends the silence as a link loss.
  checkLinkSilence(now_s);
  link_.last_activity_s = now_s;
  if (link_.up) clear(v1::FAULT_LINK_LOST, "link restored");
}

void RobotCore::onSerialState(bool open, double /*now_s*/) {
  serial_.open = open;
  if (open) {
    clear(v1::FAULT_SERIAL_DOWN, "");
  } else {
    raise(v1::FAULT_SERIAL_DOWN, "");
    estimate_.lose();
    if (moving()) latchFailsafe("serial device down");
  }
}

void RobotCore::setSerialCounters(const serial::DecoderCounters& rx, uint64_t bytes_tx, uint64_t frames_tx) {
  serial_.rx = rx;
  serial_.bytes_tx = bytes_tx;
  serial_.frames_tx = frames_tx;
}

v1::Ack RobotCore::teleop(const v1::Command& cmd, double now_s) {
  const double v = cmd.teleop().v_m_s(), w = cmd.teleop().w_rad_s();
  const auto reject = [&](const std::string& why) { return ackOf(cmd.id(), v1::Ack::REJECTED, why); };
  if (!std::isfinite(v) || !std::isfinite(w)) return reject("non-finite velocity");
  if (mode_ == v1::ESTOP) return reject("e-stop latched: resume first");
  if (mode_ == v1::FAILSAFE) return reject("failsafe latched (" + latch_reason_ + "): resume first");
  if (faults_ & v1::FAULT_SENSOR_STALE) return reject("sensor frames stale");
  if (faults_ & v1::FAULT_SERIAL_DOWN) return reject("serial device down");
  teleop_.setpoint = {std::clamp(v, -robot_.limits.max_v_m_s, robot_.limits.max_v_m_s),
                      std::clamp(w, -robot_.limits.max_w_rad_s, robot_.limits.max_w_rad_s)};
  teleop_.time_s = now_s;
  clear(v1::FAULT_COMMAND_STALE, "");
  endAutonomy();  // the operator takes over
  setMode(v1::TELEOP, "teleop set-point");
  v1::Ack ack = ackOf(cmd.id(), v1::Ack::ACCEPTED);
  if (teleop_.setpoint.v_m_s != v || teleop_.setpoint.w_rad_s != w) ack.set_reason("clamped to the robot's limits");
  return ack;
}

v1::Ack RobotCore::onCommand(const v1::Command& cmd, double now_s) {
  // Timeouts that fell due before this command first (after a stall of this
  // process the command may be handled before the timer and the frames).
  checkTimeouts(now_s);
  onLinkActivity(now_s);
  last_command_id_ = cmd.id();
  const auto reject = [&](const std::string& why) { return ackOf(cmd.id(), v1::Ack::REJECTED, why); };
  switch (cmd.kind_case()) {
    case v1::Command::kTeleop: return teleop(cmd, now_s);
    case v1::Command::kTrack:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startTrack(cmd);
    case v1::Command::kGoTo:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startGoTo(cmd);
    case v1::Command::kWheelTest:
      if (const std::string why = autonomyRefusal(); !why.empty()) return reject(why);
      return startWheelTest(cmd);
    case v1::Command::kGains: return gains_.stage(cmd, moving(), mode_);
    case v1::Command::kStop:
      clearSetpoint();
      endAutonomy();
      if (moving()) setMode(v1::IDLE, "stop");
      return ackOf(cmd.id(), v1::Ack::ACCEPTED);
    case v1::Command::kEstop:
      clearSetpoint();
      endAutonomy();
      latch_reason_ = "e-stop";
      setMode(v1::ESTOP, "e-stop from operator; needs resume");
      return ackOf(cmd.id(), v1::Ack::ACCEPTED);
    case v1::Command::kResume:
      if (mode_ == v1::NAVIGATING) route_.releaseGasHold(events_);
      if (latched()) {
        if (faults_ & v1::FAULT_SENSOR_STALE) return reject("sensor frames still stale");
        if (faults_ & v1::FAULT_SERIAL_DOWN) return reject("serial device still down");
        latch_reason_.clear();
        setMode(v1::IDLE, "resumed by operator");
      }
      return ackOf(cmd.id(), v1::Ack::ACCEPTED);
    case v1::Command::kVideo:
    case v1::Command::kPtz:
      return reject("camera commands are handled by the robot's video sender, not the motion core");
    case v1::Command::KIND_NOT_SET: break;
  }
  return reject("unknown or empty command");
}

void RobotCore::checkLinkSilence(double now_s) {
  // Tests the bit first so that no string is built on every tick.
  if (link_.up && !(faults_ & v1::FAULT_LINK_LOST) && now_s - link_.last_activity_s > safety_.link_timeout_s) {
    raise(v1::FAULT_LINK_LOST, "no heartbeat or command for " +
                                   std::to_string(static_cast<int>(safety_.link_timeout_s * 1000)) + " ms");
    if (movingAtLinkLoss()) latchFailsafe("link lost");
  }
}

void RobotCore::checkTimeouts(double now_s) {
  checkLinkSilence(now_s);
  if (mode_ == v1::TELEOP && teleop_.time_s >= 0 && now_s - teleop_.time_s > safety_.command_timeout_s) {
    raise(v1::FAULT_COMMAND_STALE, "");
    clearSetpoint();
    // With both timeouts at 300 ms, the set-point of a robot whose link went
    // silent usually expires first (the last message was a heartbeat): the
    // link loss that follows must still latch FAILSAFE, or the robot would
    // drive on when the link comes back with the console still re-sending.
    teleop_.stale_stop_s = now_s;
    setMode(v1::IDLE, "teleop set-point stale");
  }
  if (estimate_.haveFrame() && !(faults_ & v1::FAULT_SENSOR_STALE) &&
      now_s - estimate_.lastFrameS() > safety_.sensor_timeout_s) {
    // Say how long, and whether this process itself was not run for most of
    // it (a stalled host or CPU) rather than the MCU having gone quiet.
    std::string why = "no frame for " + std::to_string(std::lround((now_s - estimate_.lastFrameS()) * 1e3)) + " ms";
    if (last_run_s_ >= 0.0 && now_s - last_run_s_ > safety_.sensor_timeout_s / 2)
      why += ", this process not run for " + std::to_string(std::lround((now_s - last_run_s_) * 1e3)) + " ms";
    raise(v1::FAULT_SENSOR_STALE, why);
    if (moving()) latchFailsafe("sensor frames stale");
  }
  last_run_s_ = now_s;
}

double RobotCore::obstacleFactor() {
  const double stop = safety_.obstacle_stop_m, slow = safety_.obstacle_slow_m;
  if (!(slow > stop) || !estimate_.haveFrame()) return 1.0;
  const double nearest = estimate_.nearestFrontM(robot_.ultrasonic);
  const double f = std::clamp((nearest - stop) / (slow - stop), 0.0, 1.0);
  if (f == 0.0 && !obstacle_stopped_)
    events_.push(v1::Event::INFO, "obstacle " + std::to_string(static_cast<int>(nearest * 100)) +
                                      " cm ahead: stopped on the path until it clears");
  obstacle_stopped_ = f == 0.0;
  return f;
}

serial::WheelCommand RobotCore::computeCommand(double dt_s) {
  const bool stopped = latched() || (faults_ & v1::FAULT_SENSOR_STALE);
  if (mode_ == v1::WHEEL_TEST && !stopped) {
    // Open loop: the profile's set-points go to the MCU unslewed (the steps
    // are the point); the MCU clamps to its wheel limit.
    if (wheel_test_.active() && dt_s > 0.0) {
      const WheelTestRunner::Surroundings s{estimate_.nearestFrontM(robot_.ultrasonic), safety_.obstacle_stop_m,
                                            personFactor(), awareness_ ? awareness_->last().distance_m : 0.0};
      if (auto end = wheel_test_.step(dt_s, estimate_.pose(), s)) finishRun(std::move(*end));
      else cmd_wheels_ = wheel_test_.at();
    }
    return wheelCommand(true);
  }
  if (mode_ == v1::TRACKING && track_.active() && !stopped) {
    if (dt_s > 0.0) {
      // Eq 9: people slow the robot down on its path; anything close ahead stops it.
      const double factor = std::min(personFactor(), obstacleFactor());
      auto end = track_.step(estimate_.pose(), estimate_.measured(), factor, dt_s);
      cmd_wheels_ = track_.command();  // the tracker's own loop shapes the command
      if (end) finishRun(std::move(*end));
    }
    return wheelCommand(true);
  }
  control::Twist target;
  if (mode_ == v1::TELEOP) {
    target = teleop_.setpoint;
  } else if (mode_ == v1::NAVIGATING && route_.active() && !stopped) {
    const RouteRunner::People people{awareness_ ? &awareness_->tracker().personEchoes() : nullptr, personFactor()};
    auto step = route_.step(estimate_.pose(), estimate_.lastFrame().ultrasonic_mm, people, safety_.nav_stall_s, dt_s,
                            events_);
    if (step.end) {
      acks_.push_back(std::move(step.end->ack));
      endAutonomy();
      setMode(v1::IDLE, step.end->why);
    }
    target = step.twist;
  }
  target = control::limitTwist(target, robot_.geometry.wheel_radius_m, robot_.geometry.track_m,
                               robot_.limits.max_wheel_speed_rad_s);
  const auto want = control::wheelsFromTwist(target, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
  if (stopped) {
    cmd_wheels_ = {};  // safety stops are immediate, not slew-limited
  } else {
    // Normal starts and stops ramp symmetrically, so a timed teleop segment
    // covers exactly v * T; navigation is slewed the same way.
    const double step = robot_.limits.max_wheel_accel_rad_s2 * std::clamp(dt_s, 0.0, 0.05);
    cmd_wheels_.left_rad_s = slew(cmd_wheels_.left_rad_s, want.left_rad_s, step);
    cmd_wheels_.right_rad_s = slew(cmd_wheels_.right_rad_s, want.right_rad_s, step);
  }
  return wheelCommand(!latched());
}

serial::WheelCommand RobotCore::wheelCommand(bool enable) {
  cmd_twist_ = control::twistFromWheels(cmd_wheels_, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
  serial::WheelCommand c;
  c.left_mrad_s = toMrad(cmd_wheels_.left_rad_s);
  c.right_mrad_s = toMrad(cmd_wheels_.right_rad_s);
  c.flags = enable ? serial::WheelCommand::kEnable : 0;
  return c;
}

serial::WheelCommand RobotCore::onSensorFrame(const serial::SensorFrame& f, double now_s) {
  // The frames were stale if this one comes too late, whether or not the
  // timer saw it (after a stall of this process the backlog of old frames may
  // be read before the timer runs): latch before accepting it.
  checkTimeouts(now_s);
  const double dt_s = estimate_.onFrame(f, now_s);
  // People and gas alarms run on the MCU's clock, so that durations mean the
  // same when the simulator runs faster than real time.
  const double clock_s = estimate_.clock().control_s;
  if (awareness_) {
    std::array<double, 4> ranges{};
    for (std::size_t i = 0; i < 4; ++i)
      ranges[i] = f.ultrasonic_mm[i] == serial::kNoEcho ? -1.0 : f.ultrasonic_mm[i] * 1e-3;
    awareness_->step(estimate_.pose(), ranges, clock_s);
  }
  gas_.update(f.gas_raw, clock_s);
  if (!gas_.transitions().empty()) onGasTransitions(now_s);
  clear(v1::FAULT_SENSOR_STALE, "");
  constexpr uint16_t kSerious = serial::kFaultMotorDriver | serial::kFaultEStopButton;
  if ((f.faults & kSerious) && !(faults_ & v1::FAULT_MCU)) {
    char flags[16];
    std::snprintf(flags, sizeof flags, "0x%04x", static_cast<unsigned>(f.faults));
    raise(v1::FAULT_MCU, std::string("MCU fault flags ") + flags);
    if (moving()) latchFailsafe("MCU fault");
  } else if (!(f.faults & kSerious)) {
    clear(v1::FAULT_MCU, "");
  }
  checkTimeouts(now_s);
  applyPendingGains();  // the tick boundary: staged gains go into force together
  return computeCommand(dt_s);
}

serial::WheelCommand RobotCore::commandNow() { return computeCommand(0.0); }

std::optional<serial::WheelCommand> RobotCore::onTimer(double now_s) {
  const v1::Mode before = mode_;
  checkTimeouts(now_s);
  // No frames (stale, or the serial device closed after frames had come): no
  // gas readings either - the channels go to no_data after 0.5 s.
  if ((faults_ & (v1::FAULT_SENSOR_STALE | v1::FAULT_SERIAL_DOWN)) && estimate_.lastFrameS() >= 0.0) {
    gas_.noFrames(estimate_.clock().control_s + (now_s - estimate_.lastFrameS()));
    if (!gas_.transitions().empty()) onGasTransitions(now_s);
  }
  if (faults_ & v1::FAULT_SENSOR_STALE) return computeCommand(0.01);
  // A latch (link loss) stops the wheels now, not at the next sensor frame.
  if (mode_ != before && latched()) return computeCommand(0.0);
  return std::nullopt;
}

void RobotCore::fillTelemetry(v1::Telemetry& t, double now_s) const {
  const control::Pose2& pose = estimate_.pose();
  const control::WheelSpeeds& measured = estimate_.measured();
  const serial::SensorFrame& frame = estimate_.lastFrame();
  t.set_robot_time_us(static_cast<uint64_t>(now_s * 1e6));
  auto* p = t.mutable_pose();
  p->set_x_m(pose.x_m);
  p->set_y_m(pose.y_m);
  p->set_theta_rad(pose.theta_rad);
  t.set_gains_version(gains_.version());
  t.set_wheel_test_progress(wheel_test_.progress());
  t.set_cmd_wheel_left_rad_s(cmd_wheels_.left_rad_s);
  t.set_cmd_wheel_right_rad_s(cmd_wheels_.right_rad_s);
  // What the MCU measures is unknown (left out) until its first frame.
  if (estimate_.haveFrame()) {
    t.set_mcu_time_us(estimate_.clock().elapsed_us);
    t.set_wheel_left_rad_s(measured.left_rad_s);
    t.set_wheel_right_rad_s(measured.right_rad_s);
    const auto tw = control::twistFromWheels(measured, robot_.geometry.wheel_radius_m, robot_.geometry.track_m);
    t.set_v_m_s(tw.v_m_s);
    t.set_w_rad_s(tw.w_rad_s);
    t.set_battery_v(frame.battery_mv * 1e-3);
  }
  t.set_cmd_v_m_s(cmd_twist_.v_m_s);
  t.set_cmd_w_rad_s(cmd_twist_.w_rad_s);
  t.clear_ultrasonic_m();
  for (uint16_t mm : frame.ultrasonic_mm) t.add_ultrasonic_m(mm == serial::kNoEcho ? -1.0 : mm * 1e-3);
  t.set_grayscale(frame.grayscale);
  gas_.fillTelemetry(t, estimate_.clock().control_s, now_s);
  t.set_mode(mode_);
  t.set_faults(faults_);
  t.set_mcu_faults(frame.faults);
  auto* s = t.mutable_serial();
  s->set_frames_ok(serial_.rx.frames_ok);
  s->set_bad_cobs(serial_.rx.bad_cobs);
  s->set_bad_crc(serial_.rx.bad_crc);
  s->set_bad_length(serial_.rx.bad_length);
  s->set_unknown_id(serial_.rx.unknown_id);
  s->set_seq_gaps(serial_.rx.seq_gaps);
  s->set_overflow(serial_.rx.overflow);
  s->set_bytes_rx(serial_.rx.bytes_rx);
  s->set_bytes_tx(serial_.bytes_tx);
  s->set_frames_tx(serial_.frames_tx);
  t.set_sensor_rate_hz(estimate_.haveFrame() ? estimate_.sensorRateHz() : 0.0);
  t.set_last_command_id(last_command_id_);
  track_.fillTelemetry(t);
  route_.fillTelemetry(t, mode_ == v1::NAVIGATING);
  if (awareness_) {
    const auto& a = awareness_->last();
    t.set_pattern(static_cast<v1::HumanPattern>(static_cast<int>(a.pattern)));
    t.set_nearest_person_m(a.distance_m);
    t.set_nearest_person_speed_m_s(a.person_speed_m_s);
    t.set_speed_factor(a.speed_factor);
    t.set_people_tracked(static_cast<uint32_t>(a.people));
    // The people themselves (a cleared repeated field keeps its elements: no allocation once warm).
    t.clear_people();
    const auto* nearest = awareness_->tracker().nearest(estimate_.pose());
    for (const auto& tr : awareness_->tracker().tracks()) {
      if (!tr.isPerson()) continue;
      auto* p = t.add_people();
      p->set_id(static_cast<uint32_t>(tr.id));
      p->set_x_m(tr.x[0]);
      p->set_y_m(tr.x[1]);
      p->set_vx_m_s(tr.x[2]);
      p->set_vy_m_s(tr.x[3]);
      const bool is_nearest = &tr == nearest;
      p->set_nearest(is_nearest);
      p->set_camera_seen(awareness_->tracker().cameraSeen(tr));
      p->set_camera_hits(static_cast<uint32_t>(tr.camera_hits));
      p->set_pattern(is_nearest ? static_cast<v1::HumanPattern>(static_cast<int>(a.pattern)) : v1::PATTERN_NONE);
    }
  } else {
    t.set_speed_factor(1.0);  // no people tracking: nearest_person_m and people_tracked unknown (left out)
  }
}

}  // namespace inspect::robot
