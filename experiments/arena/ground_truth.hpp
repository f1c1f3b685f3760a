#pragma once
// The social-navigation arena's ground truth (docs/scenarios.md, "Ground
// truth"): from the simulator's true poses and velocities, the pattern of a
// person relative to the robot - what the robot's classifier should report -
// and whether any of its sonars could see the person at all. Pure.
//
// Definition (the paper's patterns, PAPER_DIGEST.md "Behaviour patterns"):
// the person's heading relative to the robot's, phi in [0, 180] degrees, and
// their place in the robot's frame (ahead x, lateral y):
// - nobody to react to (kNone): standing (speed < min_speed), behind the
//   robot, farther than max_range, or beside it beyond max_lateral;
// - crossing: phi in (crossing_min, crossing_max) = (30, 150) degrees;
// - same direction (phi <= 30): leading when on the robot's path
//   (|y| <= path_half_width), else nobody (walking alongside);
// - opposite direction (phi >= 150): confronting on the path, encountering
//   beside it (path_half_width < |y| <= max_lateral).
#include "shared/behavior/behavior_pattern.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::world {
struct World;
}

namespace inspect::arena {

struct TruthParams {
  double min_speed_m_s = 0.1;        // slower: standing, no pattern
  double crossing_min_deg = 30.0;    // relative heading strictly between these: crossing
  double crossing_max_deg = 150.0;
  double path_half_width_m = 0.6;    // robot body radius + a person's (0.35 + 0.25): on the path
  double max_lateral_m = 2.0;        // beside the path up to this: encountering (opposite) / alongside
  double max_range_m = 6.0;          // farther: nobody to react to yet
};

/// A person as the simulator knows them.
struct TruePerson {
  geometry::Vec2 position;
  geometry::Vec2 velocity;
  double radius_m = 0.25;
};

/// The pattern the robot should report for `p`, the robot at `robot` (world frame).
behavior::Pattern truePattern(const control::Pose2& robot, const TruePerson& p, const TruthParams& t = {});

/// Whether any of the four sonars could see `p`: the person's disc reaches
/// into a sensor's cone (its beam width, within its range) and no wall or
/// obstacle of `w` stands between the sensor and the person's nearest point.
bool observable(const control::Pose2& robot, const TruePerson& p, const config::UltrasonicConfig& sonar,
                const world::World& w);

}  // namespace inspect::arena
