#pragma once
// Discs (people as the ultrasonic sensors see them) and the ray cast to one.
#include <optional>

#include "shared/geometry/vec2.hpp"

namespace inspect::geometry {

/// A solid disc.
struct Circle {
  Vec2 centre;
  double radius_m = 0.0;
};

/// Distance along a ray (origin + t * dir, dir of unit length) to the first
/// point of the circle, 0 when origin lies inside it, nullopt when the ray
/// misses it or the circle lies behind.
std::optional<double> rayCircle(Vec2 origin, Vec2 dir, const Circle& c);

}  // namespace inspect::geometry
