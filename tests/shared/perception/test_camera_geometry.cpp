// What a box says on the floor (shared/perception/camera_geometry.hpp):
// bearing and foot-row range against the simulated camera's truth (tilt 0,
// where its renderer is an exact pinhole), pan turning the bearing, the exact
// pinhole model under tilt, and no range where the feet cannot be seen.
#include <gtest/gtest.h>

#include <cmath>

#include "shared/perception/camera_geometry.hpp"
#include "sim/camera_view.hpp"
#include "tests/sim/world_text.hpp"

using namespace inspect;
using perception::CameraPose;
using perception::sightingOf;

namespace {
constexpr double kRad = 3.14159265358979323846 / 180;
}

TEST(CameraGeometry, TheFigureBoxGivesTheBearingAndRangeOfTheCameraModel) {
  const sim::World empty;
  sim::CameraView view(empty, config::CameraMount{}, 640, 480);
  cv::Mat pic;
  for (const double pan : {0.0, 0.35}) {
    for (const auto& at : {sim::Vec2{5.2, 0.4}, sim::Vec2{3.5, -0.8}, sim::Vec2{8.0, 1.5}}) {
      sim::CameraScene s;
      s.pan_rad = pan;
      // The same place relative to the camera's axis, turned with the pan.
      const sim::Vec2 p{0.2 + std::cos(pan) * (at.x - 0.2) - std::sin(pan) * at.y,
                        std::sin(pan) * (at.x - 0.2) + std::cos(pan) * at.y};
      s.people.push_back({p, 0.25, 1});
      view.render(s, 1, 1, pic);
      ASSERT_EQ(view.peopleDrawn().size(), 1u);
      const auto& t = view.peopleDrawn()[0];
      CameraPose cam;
      cam.pan_rad = pan;
      const auto seen = sightingOf(t.box, cam);
      // The box of a standing person is symmetric about the body axis.
      EXPECT_NEAR(seen.bearing_rad, t.bearing_rad + pan, 0.003) << at.x << " pan " << pan;
      ASSERT_TRUE(seen.range_m);
      // The box's bottom is the soles' row: within a pixel's worth of range.
      const double px_m = t.distance_m * t.distance_m / (view.focalPx() * 0.6);
      EXPECT_NEAR(*seen.range_m, t.distance_m, 1.5 * px_m + 0.01) << at.x;
      EXPECT_NEAR(seen.x_m, p.x, 1.5 * px_m + 0.02);
      EXPECT_NEAR(seen.y_m, p.y, 1.5 * px_m + 0.02);
    }
  }
}

TEST(CameraGeometry, ThePinholeUnderTiltAndNoRangeWithoutTheFeet) {
  CameraPose cam;
  cam.tilt_rad = 8 * kRad;
  const double f = cam.focalPx();
  // A floor point 4 m ahead and 0.5 m left of the lens, through the exact tilted pinhole.
  const double X = 4.0, Y = 0.5, Z = -cam.mount.z_m;
  const double ct = std::cos(cam.tilt_rad), st = std::sin(cam.tilt_rad);
  const double depth = X * ct + Z * st, up = -X * st + Z * ct;
  const double u = 320 - f * Y / depth, v = 240 - f * up / depth;
  const cv::Rect box(static_cast<int>(std::lround(u)) - 20, static_cast<int>(std::lround(v)) - 200, 40, 200);
  const auto s = sightingOf(box, cam);
  ASSERT_TRUE(s.range_m);
  EXPECT_NEAR(*s.range_m, std::hypot(X, Y), 0.03);
  EXPECT_NEAR(s.x_m, cam.mount.x_m + X, 0.03);
  EXPECT_NEAR(s.y_m, Y, 0.03);
  // Feet cut by the picture's bottom edge: bearing only.
  EXPECT_FALSE(sightingOf(cv::Rect(300, 200, 40, 280), cam).range_m);
  // A box ending above the horizon (tilted down 20 deg, looking at a balcony): no floor there.
  CameraPose down;
  down.tilt_rad = -20 * kRad;
  EXPECT_FALSE(sightingOf(cv::Rect(300, 0, 40, 20), down).range_m);
  EXPECT_NEAR(sightingOf(cv::Rect(0, 0, 2, 20), CameraPose{}).bearing_rad, 29.9 * kRad, 0.2 * kRad)
      << "the picture's left edge: half the field of view to the left";
}

TEST(CameraGeometry, StandingHeightFromTheFootAndHeadRowsUnderTilt) {
  // A person H tall at d along the axis: the pinhole's rows of feet and head
  // (tilted by tau) give H back; a foot row at or above the horizon gives NaN.
  for (const double tilt_deg : {0.0, 10.0, -8.0}) {
    CameraPose cam;
    cam.tilt_rad = tilt_deg * kRad;
    const double f = cam.focalPx(), z = cam.mount.z_m, cy = cam.height / 2.0;
    for (const double d : {2.0, 5.0, 9.0})
      for (const double h : {1.2, 1.75}) {
        const double foot = cy + f * std::tan(std::atan(z / d) + cam.tilt_rad);
        const double head = cy - f * std::tan(std::atan((h - z) / d) - cam.tilt_rad);
        EXPECT_NEAR(perception::standingHeightM(foot, head, cam), h, 1e-9) << d << " m, tilt " << tilt_deg;
      }
    const double horizon = cy + f * std::tan(cam.tilt_rad);
    EXPECT_TRUE(std::isnan(perception::standingHeightM(horizon - 1, horizon - 100, cam))) << "tilt " << tilt_deg;
  }
}
