#pragma once
// The plane's one vector type: a point or a direction (world, odometry or
// robot frame; metres, or unitless for directions). Header-only, pure.
#include <cmath>
#include <string>

namespace inspect::geometry {

/// A point or a direction in the plane.
struct Vec2 {
  double x = 0.0;
  double y = 0.0;
};

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double k, Vec2 a) { return {k * a.x, k * a.y}; }
inline bool operator==(Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }
/// Scalar product; its sign tells acute (> 0) from obtuse (< 0) angles (Eqs 5.24, 5.27).
inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
/// z of the 3-D cross product: positive when b lies counter-clockwise of a.
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
/// Euclidean length.
inline double norm(Vec2 a) { return std::hypot(a.x, a.y); }
/// Unit vector along a; the zero vector for a (near-)zero or non-finite a.
inline Vec2 normalized(Vec2 a) {
  const double n = norm(a);
  if (!(n > 1e-12) || !std::isfinite(n)) return {};
  return {a.x / n, a.y / n};
}
/// R(angle) a: rotation counter-clockwise by angle_rad (Eq 5.23's rotation matrix).
inline Vec2 rotated(Vec2 a, double angle_rad) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  return {c * a.x - s * a.y, s * a.x + c * a.y};
}
/// Unit vector at angle angle_rad.
inline Vec2 unitAt(double angle_rad) { return {std::cos(angle_rad), std::sin(angle_rad)}; }
/// Angle of a in [-pi, pi] (atan2).
inline double angleOf(Vec2 a) { return std::atan2(a.y, a.x); }
/// True when both components are finite.
inline bool isFinite(Vec2 a) { return std::isfinite(a.x) && std::isfinite(a.y); }

/// "(x, y)" for messages about the world ("%g": "(1.5, -2)").
std::string pointText(Vec2 p);

}  // namespace inspect::geometry
