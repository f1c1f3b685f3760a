#pragma once
// Planar geometry for the world simulation: points, segments, simple polygons,
// ray casting and distances. Pure functions, table-tested.
#include <optional>
#include <string>
#include <vector>

namespace inspect::world {

/// A point or vector in the world frame, metres.
struct Vec2 {
  double x_m = 0.0;
  double y_m = 0.0;
};

inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x_m + b.x_m, a.y_m + b.y_m}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x_m - b.x_m, a.y_m - b.y_m}; }
inline Vec2 operator*(double k, Vec2 a) { return {k * a.x_m, k * a.y_m}; }
inline double dot(Vec2 a, Vec2 b) { return a.x_m * b.x_m + a.y_m * b.y_m; }
/// z component of the 3-D cross product (positive when b is CCW of a).
inline double cross(Vec2 a, Vec2 b) { return a.x_m * b.y_m - a.y_m * b.x_m; }

/// "(x, y)" for messages ("%g").
std::string pointText(Vec2 p);

/// A straight line segment from a to b.
struct Segment {
  Vec2 a;
  Vec2 b;
};

/// A closed simple polygon (convex or concave); the last vertex joins the first.
struct Polygon {
  std::vector<Vec2> vertices;
};

namespace geom {

/// Distance along a ray (origin + t * dir, dir of unit length) to a segment,
/// or nullopt when the ray misses it. Segments are two-sided; a ray parallel
/// to a segment misses it.
std::optional<double> raySegment(Vec2 origin, Vec2 dir, const Segment& s);

/// Shortest distance from a point to a segment.
double pointSegmentDistance(Vec2 p, const Segment& s);

/// True when p lies strictly inside the polygon (even-odd rule; concave polygons work).
bool pointInPolygon(Vec2 p, const Polygon& poly);

/// The polygon's edges, closing edge included.
std::vector<Segment> edgesOf(const Polygon& poly);

/// Signed area (positive for counter-clockwise vertex order).
double signedArea(const Polygon& poly);

/// True when the two segments share at least one point.
bool segmentsIntersect(const Segment& s, const Segment& t);

}  // namespace geom
}  // namespace inspect::world
