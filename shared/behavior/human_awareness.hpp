#pragma once
// The robot's awareness of people, once per control tick: ultrasonic echoes
// -> tracked people (human_tracker) -> the nearest person's behaviour pattern
// (pattern_classifier) -> the fuzzy speed factor of Eq 9 (speed_strategy).
// The factor scales the robot's speed ON its path (paper: "decelerated on the
// predetermined trajectory"). Deterministic; time is an argument.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "shared/behavior/active_look.hpp"
#include "shared/behavior/human_tracker.hpp"
#include "shared/behavior/pattern_classifier.hpp"
#include "shared/behavior/social_force.hpp"
#include "shared/behavior/speed_strategy.hpp"
#include "shared/config/config_node.hpp"

namespace inspect::behavior {

/// How people change the robot's speed.
enum class SpeedPolicy {
  kFuzzy,        // the paper's strategy: Eq 9 factor from distance, speed and pattern
  kNone,         // baseline: people are tracked and reported, the speed is never changed
  kStopAndWait,  // baseline: stop while anyone is within max_avoidance_m, full speed otherwise
  kFuzzyNoPattern,  // ablation: Eq 9 from distance and speed only, the pattern input held at the most
                    // cautious (confronting) whatever the classifier says
};
const char* toString(SpeedPolicy p);
/// Parses "fuzzy", "none", "stop_and_wait", "fuzzy_no_pattern"; throws std::invalid_argument otherwise.
SpeedPolicy parseSpeedPolicy(const std::string& s);

struct AwarenessConfig {
  bool enabled = true;  // false = SpeedPolicy::kNone
  SpeedPolicy policy = SpeedPolicy::kFuzzy;
  // The factor applied moves toward the rule base's output at most this fast,
  // so the robot's speed has no steps (jerk); falling 2/s stops from full
  // speed within 0.5 s. 0 = no limit.
  double factor_fall_per_s = 2.0;
  double factor_rise_per_s = 0.5;
  // A person beside or behind the robot (ahead of the axle by less than
  // passing_ahead_m) whose distance grows faster than passing_rate_m_s is
  // passing: they no longer interfere and the fuzzy policy keeps full speed
  // (the paper's robot "returns to its initial speed after the person passes").
  double passing_ahead_m = 0.2;
  double passing_rate_m_s = 0.1;
  // Anticipation (Eqs 7-8): the nearest person's path is predicted with the
  // social force model (walls from the map, the robot keeping its velocity)
  // over predict_horizon_s; if the predicted closest approach falls inside the
  // robot's remaining avoidance distance at that time (Eq 8: R_r,avoid - v t),
  // the strategy is given that predicted distance instead of today's.
  double predict_horizon_s = 0.5;  // about the time to stop (tau 0.2 s + the factor rate limit); 0 = off
  double robot_radius_m = 0.35;    // the robot's body as the predicted person sees it
  SocialForceParams social_force;
  std::string speed_fis = "config/fuzzy/speed_strategy.fis";
  SpeedStrategyParams speed;
  HumanTrackerParams tracker;
  PatternParams pattern;
  ActiveLookParams active_look;  // where the PTZ head looks when nobody is ahead (active_look.hpp)
};

/// What the robot knows about people this tick.
struct Awareness {
  Pattern pattern = Pattern::kNone;
  bool person = false;
  double distance_m = -1.0;      // to the nearest tracked person (centre), < 0 = none
  double person_speed_m_s = 0.0;
  double speed_factor = 1.0;     // Eq 9: 1 - dV, rate-limited: the factor applied
  double target_factor = 1.0;    // this tick's output of the policy before the rate limit
  int people = 0;                // confirmed people tracked
  bool passing = false;          // the nearest person is passing (beside or behind, moving away)
  double range_rate_m_s = 0.0;   // d(distance)/dt of the nearest person, > 0 = moving apart
  double predicted_min_m = -1.0; // predicted closest approach (centres) within the horizon, < 0 = none
  double predicted_at_s = 0.0;   // ...how far ahead
  double avoid_m = -1.0;         // Eq 8: the robot's remaining avoidance distance at that time
  bool anticipating = false;     // the predicted distance was used for the speed factor
};

/// What the speed strategy is given instead of the perception's estimate
/// (the arena's oracle policy: the simulator's true nearest person).
struct SpeedInput {
  bool person = false;
  double distance_m = -1.0;
  double speed_m_s = 0.0;
  Pattern pattern = Pattern::kNone;
};

class HumanAwareness {
 public:
  HumanAwareness(const config::UltrasonicConfig& sonar, const AwarenessConfig& cfg, SpeedStrategy strategy,
                 std::vector<geometry::Segment> map = {});
  /// One tick (pose in the odometry frame, ranges in m with < 0 = no echo).
  const Awareness& step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s);
  /// A camera picture's people (HumanTracker::observeCamera); the next step() uses them.
  void observeCamera(const control::Pose2& pose, const CameraLook& look) { tracker_.observeCamera(pose, look); }
  const Awareness& last() const { return last_; }
  /// The next step() feeds `in` to the speed policy in place of the tracked
  /// nearest person (distance, speed, pattern; no passing or anticipation);
  /// tracking and the classifier still run and are still reported. Experiments only.
  void overrideNextSpeedInput(const SpeedInput& in) { override_ = in; }
  const HumanTracker& tracker() const { return tracker_; }
  const AwarenessConfig& config() const { return cfg_; }
  const PatternClassifier& classifier() const { return classifier_; }

 private:
  /// Social force prediction of the nearest person and Eq 8 (fills the predicted_* fields of a).
  void predict(const control::Pose2& pose, const HumanTrack& n, Awareness& a);

  AwarenessConfig cfg_;
  HumanTracker tracker_;
  PatternClassifier classifier_;
  SpeedStrategy strategy_;
  Awareness last_;
  std::optional<SpeedInput> override_;
  double last_t_s_ = -1.0;
  std::vector<WallSegment> walls_;            // the map, for the prediction
  std::array<Eigen::Vector2d, 64> predicted_{};  // prediction buffer (no allocation per tick)
  control::Pose2 last_pose_;
  double robot_vx_ = 0.0, robot_vy_ = 0.0;  // low-passed from the pose (odometry frame)
};

/// Reads the `awareness:` settings (config/behavior.yaml); `base_dir` resolves a relative .fis path.
AwarenessConfig loadAwarenessConfig(const config::ConfigNode& root, const std::string& base_dir);
/// Reads config/behavior.yaml (unknown keys are errors).
AwarenessConfig loadAwarenessConfigFile(const std::string& path);

}  // namespace inspect::behavior
