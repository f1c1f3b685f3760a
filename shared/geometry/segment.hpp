#pragma once
// The plane's one segment type (walls, obstacle edges, the map's static
// segments, the gas estimator's mirrors) and what is asked of segments:
// ray casts, distances, intersections. Pure, table-tested.
#include <optional>

#include "shared/geometry/vec2.hpp"

namespace inspect::geometry {

/// A straight line segment from a to b.
struct Segment {
  Vec2 a;
  Vec2 b;
};

/// Distance along a ray (origin + t * dir, dir of unit length) to a segment,
/// or nullopt when the ray misses it. Segments are two-sided; a ray parallel
/// to a segment misses it.
std::optional<double> raySegment(Vec2 origin, Vec2 dir, const Segment& s);

/// The point of the segment nearest to p.
Vec2 closestPoint(Vec2 p, const Segment& s);

/// Shortest distance from a point to a segment.
double pointSegmentDistance(Vec2 p, const Segment& s);

/// True when the two segments cross properly: each one's ends lie strictly on
/// either side of the other (touching, collinear overlap and shared ends do
/// not count). A line of sight "passes through a wall" in this sense.
bool segmentsCross(const Segment& s, const Segment& t);

/// True when the two segments share at least one point.
bool segmentsIntersect(const Segment& s, const Segment& t);

}  // namespace inspect::geometry
