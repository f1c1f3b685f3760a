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

#include "shared/behavior/human_tracker.hpp"
#include "shared/behavior/pattern_classifier.hpp"
#include "shared/behavior/speed_strategy.hpp"
#include "shared/config/config_node.hpp"

namespace inspect::behavior {

struct AwarenessConfig {
  bool enabled = true;
  std::string speed_fis = "config/fuzzy/speed_strategy.fis";
  SpeedStrategyParams speed;
  HumanTrackerParams tracker;
  PatternParams pattern;
};

/// What the robot knows about people this tick.
struct Awareness {
  Pattern pattern = Pattern::kNone;
  bool person = false;
  double distance_m = -1.0;      // to the nearest tracked person (centre), < 0 = none
  double person_speed_m_s = 0.0;
  double speed_factor = 1.0;     // Eq 9: 1 - dV
  int people = 0;                // confirmed people tracked
};

class HumanAwareness {
 public:
  HumanAwareness(const config::UltrasonicConfig& sonar, const AwarenessConfig& cfg, SpeedStrategy strategy,
                 std::vector<MapSegment> map = {});
  /// One tick (pose in the odometry frame, ranges in m with < 0 = no echo).
  const Awareness& step(const control::Pose2& pose, const std::array<double, 4>& ranges_m, double t_s);
  const Awareness& last() const { return last_; }
  const HumanTracker& tracker() const { return tracker_; }
  const PatternClassifier& classifier() const { return classifier_; }

 private:
  AwarenessConfig cfg_;
  HumanTracker tracker_;
  PatternClassifier classifier_;
  SpeedStrategy strategy_;
  Awareness last_;
  double last_t_s_ = -1.0;
};

/// Reads the `awareness:` settings (config/behavior.yaml); `base_dir` resolves a relative .fis path.
AwarenessConfig loadAwarenessConfig(const config::ConfigNode& root, const std::string& base_dir);
/// Reads config/behavior.yaml (unknown keys are errors).
AwarenessConfig loadAwarenessConfigFile(const std::string& path);

}  // namespace inspect::behavior
