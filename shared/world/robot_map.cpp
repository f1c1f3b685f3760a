#include "shared/world/robot_map.hpp"

#include <cmath>

namespace inspect::world {

std::vector<Segment> mapFromWorld(const World& w) {
  // Odometry starts at (0, 0, 0) where the robot stands at start-up, so a
  // world point p is R(-theta0) (p - start) in the odometry frame.
  const double c = std::cos(w.start.theta_rad), s = std::sin(w.start.theta_rad);
  const auto toOdometry = [&](Vec2 p) {
    const double dx = p.x - w.start.x_m, dy = p.y - w.start.y_m;
    return Vec2{c * dx + s * dy, -s * dx + c * dy};
  };
  std::vector<Segment> map;
  for (const auto& e : solidEdges(w)) map.push_back({toOdometry(e.edge.a), toOdometry(e.edge.b)});
  return map;
}

}  // namespace inspect::world
