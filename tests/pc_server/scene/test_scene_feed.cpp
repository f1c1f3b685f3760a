// SceneFeed, the one place a robot's messages become its 3-D view for the
// live bridge and the recorder: commands draw the route, the site map follows
// SiteMaps, each camera picture's people come out once at that picture's time.
#include <gtest/gtest.h>

#include <string>

#include "pc_server/scene/scene_feed.hpp"
#include "tests/support/paths.hpp"

using namespace inspect;
using namespace inspect::server::scene;

namespace {

const ::foxglove::SceneEntity* find(const ::foxglove::SceneUpdate& u, const std::string& id) {
  for (const auto& e : u.entities())
    if (e.id() == id) return &e;
  return nullptr;
}

v1::Envelope telemetry(uint64_t capture_us) {
  v1::Envelope env;
  auto* t = env.mutable_telemetry();
  t->set_mode(v1::NAVIGATING);
  auto* p = t->mutable_perception();
  p->set_mode(v1::CAMERA_AND_SONAR);
  p->set_capture_us(capture_us);
  p->add_people()->set_bearing_rad(0.1);
  return env;
}

}  // namespace

TEST(SceneFeed, CommandsDrawTheRouteAndTelemetryTheRobot) {
  SceneFeed feed("robot1", Geometry{});
  EXPECT_EQ(find(feed.scene().scene(1), "robot/body"), nullptr) << "no robot before its telemetry";
  v1::Envelope cmd;
  auto* g = cmd.mutable_command()->mutable_go_to();
  for (const double x : {1.0, 2.0, 3.0}) g->add_points()->set_x_m(x);
  feed.onEnvelope(cmd, false);
  feed.onEnvelope(telemetry(1), true);
  const auto u = feed.scene().scene(1);
  ASSERT_NE(find(u, "robot/body"), nullptr);
  const auto* route = find(u, "route");
  ASSERT_NE(route, nullptr);
  EXPECT_EQ(route->spheres_size(), 3) << "one sphere per goal";
}

TEST(SceneFeed, TheMapFollowsSiteMapsAndTheCamerasPeopleComeOnce) {
  SceneFeed feed("robot1", Geometry{});
  SiteMaps maps;
  feed.followMap(maps, "robot1");
  EXPECT_EQ(find(feed.scene().scene(1), "map/walls")->cubes_size(), 0) << "no map yet";
  maps.setDefault(inspect::test::srcPath("config/worlds/gas_lab.yaml"));
  feed.followMap(maps, "robot1");
  EXPECT_GT(find(feed.scene().scene(1), "map/walls")->cubes_size(), 0);
  maps.set("robot1", inspect::test::srcPath("config/worlds/square_room.yaml"));
  feed.followMap(maps, "robot1");
  const int square = find(feed.scene().scene(1), "map/walls")->cubes_size();
  EXPECT_GT(square, 0);

  const auto env = telemetry(5'000'000);
  const auto people = feed.cameraPeople(env.telemetry(), 0);
  ASSERT_TRUE(people);
  EXPECT_GT(people->first, 0u);
  EXPECT_EQ(people->second.points_size() + people->second.texts_size() > 0, true);
  EXPECT_FALSE(feed.cameraPeople(env.telemetry(), 0)) << "the same picture once only";
}

TEST(SceneFeed, EachHeadsPeopleGoOnItsOwnPicturesAtItsOwnSize) {
  // docs/video.md "The wide head's stream": the wide head's boxes are stamped
  // with the wide stream's frames and scaled to its size, apart from the PTZ head's.
  SceneFeed feed("robot1", Geometry{});
  v1::Envelope env = telemetry(1'000'000);  // the PTZ head's picture of another time
  auto* t = env.mutable_telemetry();
  t->mutable_video()->set_width(640);
  t->mutable_video()->set_height(480);
  auto* w = t->mutable_wide_perception();
  w->set_mode(v1::CAMERA_AND_SONAR);
  w->set_capture_us(2'000'000);
  w->set_width(480);
  w->set_height(360);
  auto* p = w->add_people();
  p->set_box_x(240);
  p->set_box_y(90);
  p->set_box_w(48);
  p->set_box_h(96);
  p->set_bearing_rad(0.78);
  p->set_range_m(2.6);
  t->mutable_wide_video()->set_width(960);  // the stream at twice the detected size
  t->mutable_wide_video()->set_height(720);
  video::Frame f;
  f.capture_us = 2'000'000;
  feed.onAccessUnit(f, 2'000'500, 77, v1::WIDE_HEAD);  // the wide stream's frame of that picture
  const auto wide = feed.cameraPeople(*t, 0, v1::WIDE_HEAD);
  ASSERT_TRUE(wide);
  EXPECT_EQ(wide->first, 77u) << "the wide frame's timestamp";
  ASSERT_EQ(wide->second.points_size(), 1);
  EXPECT_DOUBLE_EQ(wide->second.points(0).points(0).x(), 480.0) << "box scaled 480 -> 960 wide";
  EXPECT_DOUBLE_EQ(wide->second.points(0).points(0).y(), 180.0);
  EXPECT_FALSE(feed.cameraPeople(*t, 0, v1::WIDE_HEAD)) << "once only";
  const auto ptz = feed.cameraPeople(*t, 0, v1::PTZ_HEAD);
  ASSERT_TRUE(ptz) << "the PTZ head's people come apart, once too";
  EXPECT_NE(ptz->first, 77u) << "its picture on the link's clock (no PTZ frame seen), not on the wide frame";
  EXPECT_FALSE(feed.cameraPeople(*t, 0, v1::PTZ_HEAD));
}
