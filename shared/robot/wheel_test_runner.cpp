#include "shared/robot/wheel_test_runner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "shared/control/diff_drive.hpp"

namespace inspect::robot {

std::unique_ptr<control::WheelProfile> WheelTestRunner::profileOf(const v1::WheelTest& w,
                                                                 const config::RobotConfig& robot, std::string& why) {
  std::vector<control::WheelProfileSegment> segs;
  for (int i = 0; i < w.segments_size(); ++i) {
    const auto& s = w.segments(i);
    control::WheelProfileSegment g;
    if (s.kind() == "hold") g.kind = control::WheelProfileSegment::Kind::kHold;
    else if (s.kind() == "step") g.kind = control::WheelProfileSegment::Kind::kStep;
    else if (s.kind() == "chirp") g.kind = control::WheelProfileSegment::Kind::kChirp;
    else {
      why = "segment " + std::to_string(i + 1) + ": unknown kind '" + s.kind() + "' (hold, step or chirp)";
      return nullptr;
    }
    g.duration_s = s.duration_s();
    g.left_rad_s = s.left_rad_s();
    g.right_rad_s = s.right_rad_s();
    g.f0_hz = s.f0_hz();
    g.f1_hz = s.f1_hz();
    segs.push_back(g);
  }
  // The robot's speed and turn-rate limits hold for open-loop tests too.
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const auto tw = control::twistFromWheels({segs[i].left_rad_s, segs[i].right_rad_s}, robot.geometry.wheel_radius_m,
                                             robot.geometry.track_m);
    if (std::abs(tw.v_m_s) > robot.limits.max_v_m_s + 1e-9 || std::abs(tw.w_rad_s) > robot.limits.max_w_rad_s + 1e-9) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "segment %zu (%s): %.2f m/s and %.2f rad/s exceed the robot's limits (%.2f m/s, %.2f rad/s)", i + 1,
                    control::toString(segs[i].kind), tw.v_m_s, tw.w_rad_s, robot.limits.max_v_m_s,
                    robot.limits.max_w_rad_s);
      why = buf;
      return nullptr;
    }
  }
  try {
    return std::make_unique<control::WheelProfile>(std::move(segs), robot.limits.max_wheel_speed_rad_s);
  } catch (const std::invalid_argument& e) {
    why = e.what();
    return nullptr;
  }
}

std::string WheelTestRunner::start(std::unique_ptr<control::WheelProfile> profile, const v1::WheelTest& w,
                                   uint64_t command_id, const control::Pose2& pose) {
  profile_ = std::move(profile);
  command_id_ = command_id;
  start_ = pose;
  t_s_ = 0.0;
  progress_ = 0.0;
  name_ = w.name().empty() ? "wheel test" : w.name();
  char buf[64];
  std::snprintf(buf, sizeof buf, " (%.1f s, %d segments)", profile_->duration_s(), w.segments_size());
  return name_ + buf;
}

std::optional<RunEnd> WheelTestRunner::step(double dt_s, const control::Pose2& pose, const Surroundings& s) {
  // The profile is open loop and cannot steer round anything: it ends for
  // anything inside the stop distance of a front sonar, for a person close
  // enough to slow the robot (Eq 9), and once the robot is more than
  // kRadius_m from where the test began.
  char buf[128] = "";
  const double moved = std::hypot(pose.x_m - start_.x_m, pose.y_m - start_.y_m);
  if (s.nearest_front_m < s.obstacle_stop_m)
    std::snprintf(buf, sizeof buf, "%s stopped: obstacle %.2f m ahead", name_.c_str(), s.nearest_front_m);
  else if (s.person_factor < 0.999)
    std::snprintf(buf, sizeof buf, "%s stopped: a person %.2f m away", name_.c_str(), s.person_distance_m);
  else if (moved > kRadius_m)
    std::snprintf(buf, sizeof buf, "%s stopped: %.2f m from where it began (at most %.1f m)", name_.c_str(), moved,
                  kRadius_m);
  if (buf[0]) return RunEnd{ackOf(command_id_, v1::Ack::FAILED, buf), buf};
  t_s_ += dt_s;
  progress_ = std::min(1.0, t_s_ / profile_->duration_s());
  if (t_s_ >= profile_->duration_s()) return RunEnd{ackOf(command_id_, v1::Ack::COMPLETED), name_ + " completed"};
  return std::nullopt;
}

}  // namespace inspect::robot
