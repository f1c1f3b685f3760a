#pragma once
// The navigation hybrid automaton (chapter 5.4.3, Fig 5.11) as the robot runs
// it every control tick: sonar ranges -> obstacle memory -> guards -> mode ->
// behaviour -> heading PID (Eq 5.13) -> twist. Modes GO_TO_GOAL, AVOID,
// FOLLOW_CW, FOLLOW_CCW, AT_GOAL; entering a boundary records the distance to
// the goal (the reset d_tau), leaving it needs a clear shot AND progress.
// Chattering is prevented by a minimum dwell time per mode and hysteresis on
// the AVOID and AT_GOAL guards, and counted. Deterministic: time enters only
// as dt, no clock is read, nothing is allocated after construction.
#include <cstdint>
#include <limits>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/control/pid_controller.hpp"
#include "shared/navigation/behaviours.hpp"
#include "shared/navigation/guards.hpp"
#include "shared/navigation/mode.hpp"
#include "shared/navigation/navigation_params.hpp"
#include "shared/navigation/obstacle_memory.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::navigation {

using geometry::Vec2;

/// One tick's result: the command and what telemetry shows.
struct NavigationOutput {
  control::Twist twist;                 // limited to v_max_m_s / w_max_rad_s, never backwards
  Mode mode = Mode::kAtGoal;
  FollowSide side = FollowSide::kNone;  // side chosen at the last boundary entry
  bool switched = false;                // the mode changed this tick
  uint32_t switch_count = 0;            // mode changes since the goal was set
  uint32_t rapid_switch_count = 0;      // of which within chatter_window_s of the previous one
  double time_in_mode_s = 0.0;
  double distance_to_goal_m = 0.0;
  double nearest_obstacle_m = std::numeric_limits<double>::infinity();  // reference point to nearest point
  double nearest_bearing_rad = 0.0;     // robot frame, counter-clockwise from straight ahead
  double progress_reference_m = std::numeric_limits<double>::infinity();  // d_tau (Eq 5.25)
  bool clear_shot = true;               // Eq 5.27 this tick
  bool progress = false;                // Eq 5.25 this tick
  double blend_weight = 0.0;            // avoid weight in GO_TO_GOAL with SwitchingStyle::kBlend
};

/// Navigation toward one goal at a time in the odometry frame.
class Navigator {
 public:
  /// Throws std::invalid_argument when checkParams() reports a bad parameter.
  Navigator(const NavigationParams& params, const config::UltrasonicConfig& sonar);

  /// New goal (odometry frame): GO_TO_GOAL with the counters zeroed; the obstacle memory is kept.
  void setGoal(Vec2 goal);
  /// No goal: the robot stops (AT_GOAL) until setGoal().
  void clearGoal();
  /// Forgets goal, obstacle memory and counters.
  void reset();

  /// One control tick: odometry pose, the four sonar ranges (NaN = no echo) and the time since
  /// the previous tick. A non-finite pose or dt <= 0 returns a stop without changing state.
  const NavigationOutput& step(const control::Pose2& pose, const SonarRanges& ranges_m, double dt_s);

  /// The last tick's result.
  const NavigationOutput& output() const { return out_; }
  /// The last tick's obstacle summary.
  const ObstacleSummary& obstacles() const { return obs_; }
  /// The remembered sonar points (odometry frame).
  const ObstacleMemory& memory() const { return memory_; }
  const NavigationParams& params() const { return params_; }
  bool hasGoal() const { return has_goal_; }
  Vec2 goal() const { return goal_; }

 private:
  Mode nextMode(const control::Pose2& pose, double distance_to_goal_m, Vec2 to_goal);
  void enterBoundary(const control::Pose2& pose, double distance_to_goal_m, Vec2 to_goal);
  void switchTo(Mode m);
  void resetCounters();
  control::Twist command(const control::Pose2& pose, double dt_s);
  /// The summary the followed side is steered by: the last boundary point x_o stands in
  /// for a boundary that left the memory (the end of a thin wall being rounded).
  ObstacleSummary boundaryView(const control::Pose2& pose);

  NavigationParams params_;
  config::UltrasonicConfig sonar_;
  control::PidGains heading_gains_;
  control::PidConfig heading_cfg_;
  control::PidState heading_pid_;
  ObstacleMemory memory_;
  ObstacleSummary obs_;
  NavigationOutput out_;
  Vec2 goal_;
  bool has_goal_ = false;
  Mode mode_ = Mode::kAtGoal;
  FollowSide side_ = FollowSide::kNone;
  double d_tau_m_ = std::numeric_limits<double>::infinity();
  Vec2 boundary_point_;              // last x_o of the followed boundary (odometry frame)
  bool has_boundary_point_ = false;  // ... since the current follow mode was entered
  double time_s_ = 0.0;
  double mode_since_s_ = 0.0;
  double last_switch_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace inspect::navigation
