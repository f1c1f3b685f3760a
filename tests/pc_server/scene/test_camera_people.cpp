// The camera's people over its image (pc_server/scene/camera_people): boxes
// scaled to the video's size with a label each, stamped with the picture's
// time; the clock that puts a detected picture where the video receiver put
// its frame; and the bearing rays of the 3-D scene.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "pc_server/scene/camera_people.hpp"
#include "pc_server/scene/robot_scene.hpp"

using namespace inspect;
using namespace inspect::server::scene;

namespace {

v1::Perception twoPeople() {
  v1::Perception p;
  p.set_mode(v1::CAMERA_AND_SONAR);
  p.set_capture_us(5'000'000);
  p.set_width(320);
  p.set_height(240);
  auto* a = p.add_people();
  a->set_bearing_rad(5 * std::numbers::pi / 180);
  a->set_range_m(6.2);
  a->set_x_m(6.3);
  a->set_y_m(0.55);
  a->set_box_x(100);
  a->set_box_y(40);
  a->set_box_w(32);
  a->set_box_h(64);
  auto* b = p.add_people();  // feet out of view: bearing only
  b->set_bearing_rad(-12 * std::numbers::pi / 180);
  b->set_box_x(250);
  b->set_box_y(0);
  b->set_box_w(48);
  b->set_box_h(96);
  return p;
}

}  // namespace

TEST(CameraPeople, BoxesAreScaledToTheVideoAndLabelledAtThePicturesTime) {
  const uint64_t ns = 1'700'000'000'123'456'789ULL;
  const auto a = cameraPeople(twoPeople(), 640, 480, ns);  // detected at half the video's size
  ASSERT_TRUE(a.has_timestamp());
  EXPECT_EQ(a.timestamp().seconds(), 1'700'000'000);
  EXPECT_EQ(a.timestamp().nanos(), 123'456'789);
  ASSERT_EQ(a.points_size(), 2);
  const auto& box = a.points(0);
  EXPECT_EQ(box.type(), ::foxglove::PointsAnnotation::LINE_LOOP);
  ASSERT_EQ(box.points_size(), 4);
  EXPECT_DOUBLE_EQ(box.points(0).x(), 200);
  EXPECT_DOUBLE_EQ(box.points(0).y(), 80);
  EXPECT_DOUBLE_EQ(box.points(2).x(), 264);
  EXPECT_DOUBLE_EQ(box.points(2).y(), 208);
  EXPECT_EQ(box.timestamp().nanos(), 123'456'789);
  EXPECT_GT(box.thickness(), 0);
  EXPECT_LT(a.points(1).outline_color().a(), box.outline_color().a()) << "bearing-only boxes are dimmer";
  ASSERT_EQ(a.texts_size(), 2);
  EXPECT_EQ(a.texts(0).text(), "person +5 deg 6.2 m");
  EXPECT_EQ(a.texts(1).text(), "person -12 deg, feet not in view");
  EXPECT_GE(a.texts(1).position().y(), 12) << "a box at the top edge keeps its label in the image";
  // The same size (or an unknown video size): the detector's pixels as they are.
  EXPECT_DOUBLE_EQ(cameraPeople(twoPeople(), 0, 0, ns).points(0).points(0).x(), 100);
  // Nobody seen: an empty message, which clears the boxes of the previous picture.
  v1::Perception none;
  none.set_capture_us(7);
  EXPECT_EQ(cameraPeople(none, 640, 480, ns).points_size(), 0);
}

namespace {
uint64_t plusOneSecondNs(uint64_t us) { return us * 1000 + 1'000'000'000; }  // a fixed stand-in for monoUsToWallNs
}  // namespace

TEST(CameraPeopleClock, AnnotatesEachPictureOnceWithItsFramesTimestamp) {
  CameraPeopleClock clock;
  v1::Telemetry t;
  EXPECT_FALSE(clock.fresh(t.perception(), 0, plusOneSecondNs)) << "no perception (capture time 0)";
  *t.mutable_perception() = twoPeople();  // the picture captured at robot time 5'000'000
  // Before any video: the link's offset (receive - send).
  EXPECT_EQ(clock.fresh(t.perception(), 1000, plusOneSecondNs).value_or(0), plusOneSecondNs(5'001'000));
  EXPECT_FALSE(clock.fresh(t.perception(), 1000, plusOneSecondNs)) << "the same picture again (telemetry repeats it while fresh)";
  // Frames arrive; the channel stamped them with its own times (the wall clock then).
  video::Frame f;
  for (uint64_t k = 0; k < 10; ++k) {
    f.capture_us = 5'100'000 + k * 33'333;
    clock.onAccessUnit(f, *f.capture_us + 250, 7'000'000'000 + k);
  }
  t.mutable_perception()->set_capture_us(5'100'000 + 3 * 33'333);
  EXPECT_EQ(clock.fresh(t.perception(), 1000, plusOneSecondNs).value_or(0), 7'000'000'003u) << "exactly the frame's timestamp";
  // A picture whose frame the channel did not carry (lost): the video's offset, not the link's.
  t.mutable_perception()->set_capture_us(5'090'000);
  EXPECT_EQ(clock.fresh(t.perception(), 1000, plusOneSecondNs).value_or(0), plusOneSecondNs(5'090'250));
  // An access unit without a capture time teaches nothing.
  video::Frame no_time;
  clock.onAccessUnit(no_time, 0, 9);
  t.mutable_perception()->set_capture_us(5'095'000);
  EXPECT_EQ(clock.fresh(t.perception(), 1000, plusOneSecondNs).value_or(0), plusOneSecondNs(5'095'250));
  // The ring forgets the oldest frames after kPictures.
  for (uint64_t k = 0; k < CameraPeopleClock::kPictures; ++k) {
    f.capture_us = 6'000'000 + k * 33'333;
    clock.onAccessUnit(f, *f.capture_us + 250, 8'000'000'000 + k);
  }
  t.mutable_perception()->set_capture_us(5'100'000);
  EXPECT_EQ(clock.fresh(t.perception(), 1000, plusOneSecondNs).value_or(0), plusOneSecondNs(5'100'250));
  // A robot whose clock is ahead of the server's (negative offset) still maps.
  CameraPeopleClock behind;
  f.capture_us = 9'000'000;
  behind.onAccessUnit(f, 1'000'000, 5);
  t.mutable_perception()->set_capture_us(9'500'000);
  EXPECT_EQ(behind.fresh(t.perception(), 0, plusOneSecondNs).value_or(0), plusOneSecondNs(1'500'000));
}

TEST(RobotScene, DrawsTheCamerasBearingRaysAndMarksPeopleItSees) {
  Geometry g;
  RobotScene s("robot1", g);
  v1::Telemetry t;
  t.set_mode(v1::IDLE);
  *t.mutable_perception() = twoPeople();
  auto* p = t.add_people();
  p->set_id(2);
  p->set_x_m(6.5);
  p->set_y_m(0.5);
  p->set_camera_seen(true);
  p->set_camera_hits(9);
  s.onTelemetry(t);
  const auto u = s.scene(1'000'000'000);
  std::map<std::string, const ::foxglove::SceneEntity*> by;
  for (const auto& x : u.entities()) by[x.id()] = &x;
  ASSERT_TRUE(by.contains("camera_people"));
  const auto& rays = *by["camera_people"];
  EXPECT_EQ(rays.frame_id(), "robot1/base_link");
  ASSERT_EQ(rays.lines_size(), 2);
  // Ranged: from the lens to the feet.
  EXPECT_DOUBLE_EQ(rays.lines(0).points(0).x(), g.camera_x_m);
  EXPECT_DOUBLE_EQ(rays.lines(0).points(1).x(), 6.3);
  EXPECT_DOUBLE_EQ(rays.lines(0).points(1).y(), 0.55);
  // Bearing only: along the bearing, dimmer.
  const auto& end = rays.lines(1).points(1);
  EXPECT_NEAR(std::atan2(end.y() - g.camera_y_m, end.x() - g.camera_x_m), -12 * std::numbers::pi / 180, 1e-9);
  EXPECT_LT(rays.lines(1).color().a(), rays.lines(0).color().a());
  EXPECT_EQ(rays.texts(0).text(), "camera +5 deg 6.20 m");
  ASSERT_TRUE(by.contains("people"));
  EXPECT_NE(by["people"]->texts(0).text().find("(camera)"), std::string::npos) << by["people"]->texts(0).text();
  // Without a perception the entity is there, empty (what was drawn goes away).
  v1::Telemetry bare;
  s.onTelemetry(bare);
  const auto after = s.scene(2'000'000'000);
  int entities = 0;
  for (const auto& x : after.entities())
    if (x.id() == "camera_people") {
      ++entities;
      EXPECT_EQ(x.lines_size(), 0);
    }
  EXPECT_EQ(entities, 1);
}

TEST(RobotScene, DrawsTheWideHeadsRaysFromItsOwnLensBesideThePtzHeads) {
  config::RobotConfig rc;
  rc.wide_camera = config::CameraMount{};
  rc.wide_camera->x_m = 0.3;
  rc.wide_camera->y_m = 0.05;
  const Geometry g = geometryOf(rc);
  EXPECT_DOUBLE_EQ(g.wide_camera_x_m, 0.3);
  RobotScene s("robot1", g);
  v1::Telemetry t;
  t.set_mode(v1::IDLE);
  *t.mutable_perception() = twoPeople();
  auto* w = t.mutable_wide_perception()->add_people();
  w->set_bearing_rad(std::numbers::pi / 4);
  w->set_range_m(1.7);
  w->set_x_m(0.3 + 1.2);
  w->set_y_m(0.05 + 1.2);
  s.onTelemetry(t);
  const auto u = s.scene(1'000'000'000);
  const ::foxglove::SceneEntity* rays = nullptr;
  for (const auto& x : u.entities())
    if (x.id() == "camera_people") rays = &x;
  ASSERT_NE(rays, nullptr);
  ASSERT_EQ(rays->lines_size(), 3) << "two of the PTZ head, one of the wide head";
  const auto& wide = rays->lines(2);
  EXPECT_DOUBLE_EQ(wide.points(0).x(), 0.3);
  EXPECT_DOUBLE_EQ(wide.points(0).y(), 0.05);
  EXPECT_DOUBLE_EQ(wide.points(1).x(), 1.5);
  EXPECT_NE(wide.color().b(), rays->lines(0).color().b()) << "the heads in their own colours";
  EXPECT_EQ(rays->texts(2).text(), "wide +45 deg 1.70 m");
}
