#pragma once
// Circles (people seen by the ultrasonic sensors) and ray/circle intersection.
#include <optional>

#include "sim/world_names.hpp"

namespace inspect::sim {

/// A solid disc in the world frame.
struct Circle {
  Vec2 centre;
  double radius_m = 0.0;
};

namespace geom {

/// Distance along a ray (origin + t * dir, dir of unit length) to the first
/// point of the circle, 0 when origin lies inside it, nullopt when the ray
/// misses it or the circle lies behind.
std::optional<double> rayCircle(Vec2 origin, Vec2 dir, const Circle& c);

}  // namespace geom
}  // namespace inspect::sim
