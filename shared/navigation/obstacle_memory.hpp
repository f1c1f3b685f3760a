#pragma once
// Obstacle perception from the four ultrasonic ranges only: each valid range
// becomes a point (robot frame, from the mount pose: on the beam axis, or on
// the ray toward a known wall's normal), is moved into the odometry frame and
// kept for a short time in a fixed ring buffer, so the side sensors and recent
// front readings together describe a wall while the robot turns. summarise()
// reduces the remembered points to what the behaviours and guards need: the
// avoid vector (Eq 5.20 summed over points), the nearest point, whether the
// way to the goal is free, and per side the boundary to follow (docs/navigation.md).
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include "shared/config/robot_config.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/navigation/navigation_params.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::navigation {

using geometry::Vec2;

/// Number of ultrasonic sensors, in the wire order front-left, front-right, left, right.
inline constexpr std::size_t kSonarCount = 4;
/// Ranges in metres; NaN (or anything outside the sensor's range) = no echo.
using SonarRanges = std::array<double, kSonarCount>;

/// Wire millimetres (serial::kNoEcho = no echo) to metres (NaN = no echo).
SonarRanges rangesFromMm(const std::array<uint16_t, kSonarCount>& range_mm);

/// Robot-frame obstacle point of one reading, or nullopt when the range is not finite,
/// outside [min_range_m, max_range_m] or beyond max_use_m. The point lies on the beam axis,
/// or - given the direction (robot frame) of the normal toward a flat wall the sensor
/// faces - on the ray of the cone closest to that normal, where a flat wall echoes from.
std::optional<Vec2> sonarPoint(const config::UltrasonicMount& mount, const config::UltrasonicConfig& sonar,
                               double range_m, double max_use_m,
                               std::optional<double> wall_normal_rad = std::nullopt);

/// A robot-frame point expressed in the odometry frame of `pose`.
Vec2 toOdometryFrame(const control::Pose2& pose, Vec2 robot_point);

/// The boundary on one side of the robot, from the remembered points on that side or in the
/// front sector within follow_caution_m: the obstacle point x_o of Eq 5.20 is the nearest
/// point of a segment fitted to them (a wall seen by a sonar sweeping along it), or - when
/// they do not lie on a line (a corner, a post) - their closeness-weighted direction.
struct SideView {
  double nearest_m = std::numeric_limits<double>::infinity();  // nearest point on this side
  Vec2 away_from_nearest;      // unit, zero when none
  Vec2 avoid;                  // unit (x - x_o), zero when no point is within follow_caution_m
  double distance_m = std::numeric_limits<double>::infinity();  // |x - x_o|
  bool line_fit = false;       // x_o came from a fitted segment
};

/// What the remembered obstacle points mean for the robot at one instant (odometry frame).
struct ObstacleSummary {
  bool any = false;            // at least one point is remembered
  double nearest_m = std::numeric_limits<double>::infinity();  // reference point to nearest point
  double nearest_bearing_rad = 0.0;  // direction of the nearest point, robot frame
  Vec2 nearest_point;          // odometry frame
  Vec2 away_from_nearest;      // unit vector from the nearest point to the robot (zero when none)
  Vec2 avoid;                  // Eq 5.20 over the points within caution distance: closeness-weighted
                               // mean of unit (x - x_o); |avoid| <= 1, zero when none
  int points_in_caution = 0;   // points that made `avoid`
  bool goal_blocked = false;   // a point lies in the corridor toward the goal, within the guard distance
                               // and short of the goal (a point beyond the goal is not in the way)
  bool goal_near = false;      // the goal lies within the guard distance: that corridor covers the whole way
  SideView right;              // bearings <= +follow_front_sector_rad (obstacle followed clockwise)
  SideView left;               // bearings >= -follow_front_sector_rad (obstacle followed counter-clockwise)
};

/// Short-lived memory of obstacle points: fixed capacity, no allocation after construction.
class ObstacleMemory {
 public:
  /// Oldest points are overwritten when more than this many are younger than memory_s.
  static constexpr std::size_t kCapacity = 1024;

  /// Drops the points older than max_age_s at now_s.
  void expire(double now_s, double max_age_s);
  /// Remembers a point (odometry frame) seen at t_s; times must not decrease.
  void add(Vec2 point, double t_s);
  /// Forgets everything.
  void clear();
  /// Number of remembered points.
  std::size_t size() const { return count_; }
  /// A remembered point and when it was seen.
  struct Stamped {
    Vec2 p;
    double t_s = 0.0;
  };
  /// The i-th point, oldest first (i < size()).
  const Stamped& at(std::size_t i) const { return buf_[(tail_ + i) % kCapacity]; }
  /// The i-th point's position.
  Vec2 point(std::size_t i) const { return at(i).p; }

 private:
  std::array<Stamped, kCapacity> buf_{};
  std::size_t tail_ = 0;  // index of the oldest point
  std::size_t count_ = 0;
};

/// Reduces the memory to the summary for the robot at `pose` heading for `goal` (odometry
/// frame) at time now_s (same clock as ObstacleMemory::add).
ObstacleSummary summarise(const ObstacleMemory& memory, const control::Pose2& pose, Vec2 goal, double now_s,
                          const NavigationParams& params);

}  // namespace inspect::navigation
