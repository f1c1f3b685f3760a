#pragma once
// What the simulation reports for the ground-truth log (and for tests).
#include <cstdint>
#include <optional>
#include <span>
#include <string>
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

/// Gas at the robot's sampling inlet (10 Hz of sim time), one value per configured channel in slot order.
struct GasSample {
  double sim_t_s = 0.0;
  double inlet_x_m = 0.0;             // inlet position, world frame
  double inlet_y_m = 0.0;
  std::span<const double> true_value;  // background + gas + cross-sensitivities, before the sensor's response
  std::span<const double> reading;     // what the frame carries: raw x scale; NaN = no data (dropout)
};

/// The detail of a `ptz` event (docs/simulator.md): the camera mount's new
/// target, and the PtzCommand's flags where they are known (the emulator; the
/// firmware in the loop reports only the target it took).
inline std::string ptzEventDetail(int32_t pan_0p1mrad, int32_t tilt_0p1mrad, std::optional<int> flags = std::nullopt) {
  std::string d = "pan_0p1mrad=" + std::to_string(pan_0p1mrad) + " tilt_0p1mrad=" + std::to_string(tilt_0p1mrad);
  if (flags) d += " flags=" + std::to_string(*flags);
  return d;
}

/// Receives the simulation's ground truth, commands and events. Default: ignore.
class SimObserver {
 public:
  virtual ~SimObserver() = default;
  /// Once per sensor frame.
  virtual void onSample(const TruthSample& /*sample*/) {}
  /// Every wheel command the MCU accepted (exact wire integers).
  virtual void onCommand(double /*sim_t_s*/, uint8_t /*seq*/, const serial::WheelCommand& /*cmd*/) {}
  /// A named event (start, watchdog_trip, watchdog_clear, host_silent, collision, collision_person,
  /// pedestrian_start, pedestrian_end, gas_channels, gas_source, gas_fault_start, gas_fault_end, ptz, stop).
  virtual void onEvent(double /*sim_t_s*/, std::string_view /*event*/, std::string_view /*detail*/) {}
  /// Every sensor frame the MCU sent: its wire bytes (COBS, with the 0x00 delimiter) and MCU time.
  virtual void onFrameSent(double /*sim_t_s*/, std::span<const uint8_t> /*wire*/, uint32_t /*mcu_time_ms*/) {}
  /// Each present pedestrian, every 100 ms of sim time.
  virtual void onPedestrian(const PedestrianSample& /*sample*/) {}
  /// The gas channels at the inlet, every 100 ms of sim time (when any channel is configured).
  virtual void onGas(const GasSample& /*sample*/) {}
};

}  // namespace inspect::sim
