// The plane's types and questions (shared/geometry): ray casts, distances,
// crossings against touching, polygons, circles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "shared/geometry/circle.hpp"
#include "shared/geometry/polygon.hpp"
#include "shared/geometry/segment.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::geometry {
namespace {

TEST(Vec2, Operations) {
  const Vec2 a{3, 4};
  EXPECT_DOUBLE_EQ(norm(a), 5.0);
  EXPECT_DOUBLE_EQ(dot(a, {1, 0}), 3.0);
  EXPECT_DOUBLE_EQ(cross({1, 0}, {0, 1}), 1.0);  // counter-clockwise: positive
  EXPECT_NEAR(norm(normalized(a)), 1.0, 1e-15);
  EXPECT_EQ(normalized({0, 0}), (Vec2{0, 0}));
  EXPECT_EQ(normalized({NAN, 1}), (Vec2{0, 0}));
  const Vec2 r = rotated({1, 0}, std::numbers::pi / 2);
  EXPECT_NEAR(r.x, 0.0, 1e-15);
  EXPECT_NEAR(r.y, 1.0, 1e-15);
  EXPECT_NEAR(angleOf(unitAt(2.0)), 2.0, 1e-15);
  EXPECT_FALSE(isFinite({INFINITY, 0}));
  EXPECT_EQ(pointText({1.5, -2}), "(1.5, -2)");
}

TEST(Segment, RayCast) {
  const Segment wall{{2, -1}, {2, 1}};
  EXPECT_DOUBLE_EQ(*raySegment({0, 0}, {1, 0}, wall), 2.0);
  EXPECT_FALSE(raySegment({0, 0}, {-1, 0}, wall));         // behind
  EXPECT_FALSE(raySegment({0, 0}, {0, 1}, wall));          // parallel
  EXPECT_FALSE(raySegment({0, 1.5}, {1, 0}, wall));        // past its end
  EXPECT_DOUBLE_EQ(*raySegment({0, 1}, {1, 0}, wall), 2.0);  // its end counts
}

TEST(Segment, ClosestPointAndDistance) {
  const Segment s{{0, 0}, {4, 0}};
  EXPECT_EQ(closestPoint({1, 3}, s), (Vec2{1, 0}));
  EXPECT_EQ(closestPoint({-2, 1}, s), (Vec2{0, 0}));  // clamped to an end
  EXPECT_DOUBLE_EQ(pointSegmentDistance({7, 4}, s), 5.0);
  EXPECT_DOUBLE_EQ(pointSegmentDistance({1, 1}, Segment{{2, 2}, {2, 2}}), std::sqrt(2.0));  // a point
}

TEST(Segment, CrossingIsStrictIntersectingIsNot) {
  const Segment s{{0, 0}, {2, 0}};
  EXPECT_TRUE(segmentsCross(s, {{1, -1}, {1, 1}}));
  EXPECT_TRUE(segmentsIntersect(s, {{1, -1}, {1, 1}}));
  // Touching at an end: intersects, does not cross (a line of sight grazing a wall's end).
  EXPECT_FALSE(segmentsCross(s, {{1, 0}, {1, 1}}));
  EXPECT_TRUE(segmentsIntersect(s, {{1, 0}, {1, 1}}));
  // Collinear overlap: intersects, does not cross.
  EXPECT_FALSE(segmentsCross(s, {{1, 0}, {3, 0}}));
  EXPECT_TRUE(segmentsIntersect(s, {{1, 0}, {3, 0}}));
  EXPECT_FALSE(segmentsIntersect(s, {{3, -1}, {3, 1}}));
}

TEST(Polygon, ConcaveInsideAreaAndEdges) {
  // An L: the notch at (1.5, 1.5) is outside.
  const Polygon l{{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}};
  EXPECT_TRUE(pointInPolygon({0.5, 1.5}, l));
  EXPECT_TRUE(pointInPolygon({1.5, 0.5}, l));
  EXPECT_FALSE(pointInPolygon({1.5, 1.5}, l));
  EXPECT_DOUBLE_EQ(signedArea(l), 3.0);
  Polygon cw = l;
  std::reverse(cw.vertices.begin(), cw.vertices.end());
  EXPECT_DOUBLE_EQ(signedArea(cw), -3.0);
  const auto edges = edgesOf(l);
  ASSERT_EQ(edges.size(), 6u);
  EXPECT_EQ(edges.back().b, (Vec2{0, 0}));  // the closing edge
}

TEST(Circle, RayCast) {
  const Circle person{{3, 0}, 0.5};
  EXPECT_DOUBLE_EQ(*rayCircle({0, 0}, {1, 0}, person), 2.5);
  EXPECT_DOUBLE_EQ(*rayCircle({3.1, 0}, {1, 0}, person), 0.0);  // inside
  EXPECT_FALSE(rayCircle({0, 0}, {-1, 0}, person));             // behind
  EXPECT_FALSE(rayCircle({0, 1}, {1, 0}, person));              // misses
}

}  // namespace
}  // namespace inspect::geometry
