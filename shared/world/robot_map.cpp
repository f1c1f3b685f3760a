#include "shared/world/robot_map.hpp"

#include <cmath>

namespace inspect::world {

std::vector<behavior::MapSegment> mapFromWorld(const World& w) {
  // Odometry starts at (0, 0, 0) where the robot stands at start-up, so a
  // world point p is R(-theta0) (p - start) in the odometry frame.
  const double c = std::cos(w.start.theta_rad), s = std::sin(w.start.theta_rad);
  const auto toOdometry = [&](const Eigen::Vector2d& p) {
    const double dx = p.x() - w.start.x_m, dy = p.y() - w.start.y_m;
    return Eigen::Vector2d(c * dx + s * dy, -s * dx + c * dy);
  };
  std::vector<behavior::MapSegment> map;
  for (const auto& e : solidEdges(w)) {
    const Eigen::Vector2d a = toOdometry(e.a_m), b = toOdometry(e.b_m);
    map.push_back({a.x(), a.y(), b.x(), b.y()});
  }
  return map;
}

}  // namespace inspect::world
