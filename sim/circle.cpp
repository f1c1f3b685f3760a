#include "sim/circle.hpp"

#include <cmath>

namespace inspect::sim::geom {

std::optional<double> rayCircle(Vec2 origin, Vec2 dir, const Circle& c) {
  // |origin + t dir - centre|^2 = r^2 with |dir| = 1: t^2 + 2 b t + k = 0.
  const Vec2 oc = origin - c.centre;
  const double k = dot(oc, oc) - c.radius_m * c.radius_m;
  if (k <= 0.0) return 0.0;
  const double b = dot(oc, dir);
  if (b >= 0.0) return std::nullopt;  // outside and heading away
  const double disc = b * b - k;
  if (disc < 0.0) return std::nullopt;
  return -b - std::sqrt(disc);
}

}  // namespace inspect::sim::geom
