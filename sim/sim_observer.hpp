#pragma once
// What the simulation reports for the ground-truth log (and for tests).
#include <cstdint>
#include <string_view>

#include "shared/control/diff_drive.hpp"
#include "shared/serial/messages.hpp"

namespace inspect::sim {

/// Ground truth at one sensor frame.
struct TruthSample {
  double sim_t_s = 0.0;
  control::Pose2 pose;
  control::WheelSpeeds wheel;     // actual wheel speeds
  control::WheelSpeeds setpoint;  // set-points the MCU applies
  uint16_t faults = 0;            // serial::McuFault bits sent in the frame
};

/// Ground truth of one present pedestrian (10 Hz of sim time).
struct PedestrianSample {
  double sim_t_s = 0.0;
  std::string_view id;
  double x_m = 0.0;
  double y_m = 0.0;
  double vx_m_s = 0.0;
  double vy_m_s = 0.0;
  double robot_distance_m = 0.0;  // centre of the person to the centre of the robot's body circle
};

/// Receives the simulation's ground truth, commands and events. Default: ignore.
class SimObserver {
 public:
  virtual ~SimObserver() = default;
  /// Once per sensor frame.
  virtual void onSample(const TruthSample& /*sample*/) {}
  /// Every wheel command the MCU accepted (exact wire integers).
  virtual void onCommand(double /*sim_t_s*/, uint8_t /*seq*/, const serial::WheelCommand& /*cmd*/) {}
  /// A named event (start, watchdog_trip, watchdog_clear, host_silent, collision, collision_person,
  /// pedestrian_start, pedestrian_end, ptz, stop).
  virtual void onEvent(double /*sim_t_s*/, std::string_view /*event*/, std::string_view /*detail*/) {}
  /// Each present pedestrian, every 100 ms of sim time.
  virtual void onPedestrian(const PedestrianSample& /*sample*/) {}
};

}  // namespace inspect::sim
