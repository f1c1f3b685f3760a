#pragma once
// Closed simple polygons (obstacles, room outlines). Pure, table-tested.
#include <vector>

#include "shared/geometry/segment.hpp"

namespace inspect::geometry {

/// A closed simple polygon (convex or concave); the last vertex joins the first.
struct Polygon {
  std::vector<Vec2> vertices;
};

/// True when p lies strictly inside the polygon (even-odd rule; concave polygons work).
bool pointInPolygon(Vec2 p, const Polygon& poly);

/// The polygon's edges, closing edge included.
std::vector<Segment> edgesOf(const Polygon& poly);

/// Signed area (positive for counter-clockwise vertex order).
double signedArea(const Polygon& poly);

}  // namespace inspect::geometry
