#pragma once
// Trajectory tracking as the robot runs it every tick (paper Fig 9):
// reference path -> error (Eq 10) -> auxiliary kinematic controller (Eq 12)
// -> wheel speed references (Eq 13) -> per-wheel PID or fuzzy-PID (Eqs 14-15)
// -> wheel commands. Deterministic: time enters only as dt.
#include <memory>
#include <string>

#include "shared/control/diff_drive.hpp"
#include "shared/control/fuzzy_pid.hpp"
#include "shared/control/reference_path.hpp"
#include "shared/control/tracking_controller.hpp"

namespace inspect::control {

/// Which wheel-speed controller turns wheel references into commands.
enum class WheelControl {
  kDirect,    // the reference is the command (the MCU's speed loop does the rest)
  kPid,       // Eq 14 with the base gains kp', ki', kd'
  kFuzzyPid,  // Eqs 14-15
};
const char* toString(WheelControl c);

/// Everything the tracker needs besides the path.
struct TrackerParams {
  AuxiliaryGains aux;
  WheelControl wheel_control = WheelControl::kFuzzyPid;
  bool feedforward = true;   // command = reference + controller output (else controller output only)
  FuzzyPidParams fuzzy;      // .base holds the PID gains for kPid too
  PidConfig pid;
  double wheel_radius_m = 0.2;
  double track_m = 0.438;
  double max_wheel_speed_rad_s = 5.0;
};

/// One tick's result.
struct TrackerOutput {
  WheelSpeeds command;      // to send to the MCU
  WheelSpeeds reference;    // Eq 13 from the auxiliary controller's twist
  Twist twist;              // Eq 12 output
  ReferenceState ref;       // where the reference is now
  TrackingError error;      // Eq 10
  bool done = false;        // the path is complete (commands are zero)
};

class TrajectoryTracker {
 public:
  /// `scheduler` may be null unless wheel_control is kFuzzyPid.
  TrajectoryTracker(std::unique_ptr<ReferencePath> path, const TrackerParams& params,
                    std::shared_ptr<FuzzyGainScheduler> scheduler);

  /// One control tick: robot pose and measured wheel speeds in, commands out.
  /// speed_factor in [0, 1] slows progress along the path (fuzzy speed strategy).
  TrackerOutput step(const Pose2& pose, const WheelSpeeds& measured, double speed_factor, double dt_s);

  /// New gains (and, when not null, a new fuzzy system) from the next step on.
  /// The wheel loops keep their state: the integral is stored as a term
  /// (ki * integral of e), so a change of ki does not bump the output.
  void setGains(const FuzzyPidParams& fuzzy, const AuxiliaryGains& aux,
                std::shared_ptr<FuzzyGainScheduler> scheduler = nullptr);

  const ReferencePath& path() const { return *path_; }
  const PathProgress& progress() const { return progress_; }
  /// Gains in force on each wheel in the last step (fuzzy-scheduled or base).
  PidGains lastGains(int wheel) const;

 private:
  double wheelStep(int i, double ref, double meas, double dt_s);

  std::unique_ptr<ReferencePath> path_;
  TrackerParams p_;
  std::shared_ptr<FuzzyGainScheduler> sched_;
  PathProgress progress_;
  FuzzyPidState wheel_[2];
};

}  // namespace inspect::control
