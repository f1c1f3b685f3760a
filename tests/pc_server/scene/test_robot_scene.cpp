// A robot's 3-D scene (pc_server/scene/robot_scene): the frames and their
// transforms, the entities drawn from telemetry, routes and alarms, the gas
// grid's layout, events as log lines.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "pc_server/scene/robot_scene.hpp"

using namespace inspect;
using namespace inspect::server::scene;

namespace {

v1::Hello sceneHello() {
  v1::Hello h;
  h.set_robot_id("robot1");
  auto* ch = h.add_gas_channels();
  ch->set_name("CH4");
  ch->set_alarm_low(10);
  ch->set_alarm_high(20);
  ch->set_range_max(100);
  ch->set_t90_s(0);  // no lag to undo: the grid holds the readings
  h.set_gas_inlet_x_m(0.3);
  return h;
}

v1::Telemetry sceneTelemetry(double t_s, double x, double gas) {
  v1::Telemetry t;
  t.set_robot_time_us(static_cast<uint64_t>(t_s * 1e6));
  t.mutable_pose()->set_x_m(x);
  t.mutable_pose()->set_theta_rad(std::numbers::pi / 2);
  t.set_mode(v1::NAVIGATING);
  for (double r : {1.2, -1.0, 0.8, 3.0}) t.add_ultrasonic_m(r);
  t.add_gas(gas);
  t.set_ptz_pan_rad(0.5);
  t.set_ptz_tilt_rad(0.2);
  auto* p = t.add_people();
  p->set_id(4);
  p->set_x_m(2);
  p->set_y_m(1);
  p->set_vx_m_s(-0.8);
  p->set_pattern(v1::CONFRONTING);
  p->set_nearest(true);
  return t;
}

const ::foxglove::FrameTransform* find(const ::foxglove::FrameTransforms& f, const std::string& child) {
  for (const auto& t : f.transforms())
    if (t.child_frame_id() == child) return &t;
  return nullptr;
}

}  // namespace

TEST(RobotScene, TransformsChainMapOdomBaseSensorsCamera) {
  RobotScene s("robot1", Geometry{});
  SiteMap m;
  m.start_x_m = 1;
  m.start_y_m = 2;
  m.start_theta_rad = std::numbers::pi;
  s.setMap(m);
  s.onHello(sceneHello());
  s.onTelemetry(sceneTelemetry(1.0, 0.5, 0));
  const auto f = s.transforms(1'500'000'000);
  const auto* odom = find(f, "robot1/odom");
  ASSERT_NE(odom, nullptr);
  EXPECT_EQ(odom->parent_frame_id(), "map");
  EXPECT_DOUBLE_EQ(odom->translation().x(), 1);
  EXPECT_NEAR(odom->rotation().z(), 1.0, 1e-12);  // yaw pi
  const auto* base = find(f, "robot1/base_link");
  ASSERT_NE(base, nullptr);
  EXPECT_EQ(base->parent_frame_id(), "robot1/odom");
  EXPECT_DOUBLE_EQ(base->translation().x(), 0.5);
  EXPECT_NEAR(base->rotation().w(), std::cos(std::numbers::pi / 4), 1e-12);
  EXPECT_EQ(base->timestamp().seconds(), 1);
  EXPECT_EQ(base->timestamp().nanos(), 500'000'000);
  for (const char* sonar : kSonarNames) ASSERT_NE(find(f, std::string("robot1/") + sonar), nullptr) << sonar;
  const auto* mount = find(f, "robot1/camera_mount");
  ASSERT_NE(mount, nullptr);
  EXPECT_NEAR(mount->rotation().z(), std::sin(0.25), 1e-12);  // pan 0.5 rad
  const auto* cam = find(f, "robot1/camera");
  ASSERT_NE(cam, nullptr);
  EXPECT_EQ(find(f, "robot1/camera_wide"), nullptr) << "no wide head in this robot's config: no frame for one";
  Geometry wide;
  wide.wide_camera = true;
  RobotScene w("robot1", wide);
  w.onTelemetry(sceneTelemetry(1.0, 0.5, 0));
  const auto wf = w.transforms(1'500'000'000);
  const auto* wide_cam = find(wf, "robot1/camera_wide");
  ASSERT_NE(wide_cam, nullptr);
  EXPECT_EQ(wide_cam->parent_frame_id(), "robot1/base_link");
  EXPECT_DOUBLE_EQ(wide_cam->translation().z(), 0.55);
  // Every rotation is a unit quaternion (proto3's unset quaternion, w = 0, is not).
  for (const auto& t : f.transforms()) {
    const auto& q = t.rotation();
    EXPECT_NEAR(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z(), 1.0, 1e-9) << t.child_frame_id();
  }
}

TEST(RobotScene, DrawsTheMapRobotSonarsPeopleRouteAndAlarms) {
  RobotScene s("robot1", Geometry{});
  SiteMap m;
  m.walls = {{{0, 0}, {4, 0}}};
  m.obstacles = {{{1, 1}, {2, 1}}};
  s.setMap(m);
  s.onHello(sceneHello());
  v1::Command c;
  auto* g = c.mutable_go_to();
  auto* p = g->add_points();
  p->set_x_m(2);
  p->set_label("valve A");
  p->set_dwell_s(10);
  g->add_points()->set_x_m(4);
  s.onCommand(c);
  s.onTelemetry(sceneTelemetry(1.0, 0.5, 0));
  v1::Event e;
  e.set_kind(v1::Event::ALARM_RAISED);
  e.mutable_gas_alarm()->set_id(9);
  e.mutable_gas_alarm()->set_channel_name("CH4");
  e.mutable_gas_alarm()->set_level(v1::GasAlarm::HIGH);
  e.mutable_gas_alarm()->set_value(25);
  e.mutable_gas_alarm()->set_unit("%LEL");
  e.mutable_gas_alarm()->mutable_pose()->set_x_m(1.5);
  s.onEvent(e);
  const auto u = s.scene(2'000'000'000);
  std::map<std::string, const ::foxglove::SceneEntity*> by;
  for (const auto& x : u.entities()) by[x.id()] = &x;
  ASSERT_TRUE(by.contains("map/walls"));
  EXPECT_EQ(by["map/walls"]->frame_id(), "map");
  EXPECT_EQ(by["map/walls"]->cubes_size(), 1);
  EXPECT_NEAR(by["map/walls"]->cubes(0).size().x(), 4.06, 1e-9);  // the wall's length plus its thickness
  ASSERT_TRUE(by.contains("robot/body"));
  EXPECT_TRUE(by["robot/body"]->frame_locked());
  EXPECT_EQ(by["robot/body"]->frame_id(), "robot1/base_link");
  // Sonar beams: an echo draws to its range with a label, no echo draws faint to the maximum, unlabelled.
  ASSERT_TRUE(by.contains("robot/sonar_fl") && by.contains("robot/sonar_fr"));
  EXPECT_EQ(by["robot/sonar_fl"]->texts(0).text(), "1.20 m");
  EXPECT_EQ(by["robot/sonar_fr"]->texts_size(), 0);
  const auto& people = *by["people"];
  EXPECT_EQ(people.frame_id(), "robot1/odom");
  ASSERT_EQ(people.cylinders_size(), 1);
  EXPECT_DOUBLE_EQ(people.cylinders(0).pose().position().x(), 2);
  EXPECT_NE(people.texts(0).text().find("confronting"), std::string::npos);
  EXPECT_EQ(people.lines_size(), 3);  // proxemic rings
  const auto& route = *by["route"];
  EXPECT_EQ(route.spheres_size(), 2);
  EXPECT_EQ(route.texts(0).text(), "1 valve A (10 s)");
  const auto& alarms = *by["gas/alarms"];
  ASSERT_EQ(alarms.texts_size(), 1);
  EXPECT_EQ(alarms.texts(0).text(), "CH4 HIGH 25.0 %LEL");
  e.set_kind(v1::Event::ALARM_CLEARED);
  e.mutable_gas_alarm()->mutable_pose()->set_x_m(3);  // cleared elsewhere: the marker stays where it was raised
  s.onEvent(e);
  const auto u2 = s.scene(0);
  for (const auto& x : u2.entities())
    if (x.id() == "gas/alarms") {
      EXPECT_EQ(x.texts(0).text(), "CH4 HIGH 25.0 %LEL (cleared)");
      EXPECT_DOUBLE_EQ(x.cylinders(0).pose().position().x(), 1.5);
    }
}

TEST(RobotScene, GasGridHasTheReadingsWhereTheInletWas) {
  RobotScene s("robot1", Geometry{});
  s.onHello(sceneHello());
  EXPECT_TRUE(s.gridChannels().empty());
  for (int i = 0; i < 100; ++i) s.onTelemetry(sceneTelemetry(i * 0.05, 0, 15.0));  // standing still: 15 %LEL
  ASSERT_EQ(s.gridChannels(), std::vector<std::string>{"CH4"});
  const auto g = s.grid("CH4", 0);
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->frame_id(), "robot1/odom");
  EXPECT_EQ(g->cell_stride(), 8u);
  EXPECT_EQ(g->row_stride(), g->column_count() * 8);
  ASSERT_EQ(g->fields_size(), 5);
  EXPECT_EQ(g->fields(0).name(), "value");
  EXPECT_EQ(g->fields(4).name(), "alpha");
  ASSERT_EQ(g->data().size() % g->row_stride(), 0u);
  // The inlet: 0.3 m ahead of (0, 0) facing +y is (0, 0.3).
  const double cx = (0 - g->pose().position().x()) / g->cell_size().x();
  const double cy = (0.3 - g->pose().position().y()) / g->cell_size().y();
  const std::size_t at = static_cast<std::size_t>(cy) * g->row_stride() + static_cast<std::size_t>(cx) * 8;
  float v = 0;
  std::memcpy(&v, g->data().data() + at, 4);
  EXPECT_NEAR(v, 15.0, 1e-3);
  EXPECT_GT(static_cast<uint8_t>(g->data()[at + 7]), 0);  // drawn
  EXPECT_FALSE(s.grid("H2S", 0).has_value());
}

TEST(RobotScene, EventsAsLogLines) {
  v1::Event e;
  e.set_kind(v1::Event::ALARM_RAISED);
  e.set_text("CH4 HIGH");
  e.mutable_gas_alarm()->set_level(v1::GasAlarm::HIGH);
  const auto l = RobotScene::log("robot1", e, 3'000'000'001);
  EXPECT_EQ(l.level(), ::foxglove::Log::ERROR);
  EXPECT_EQ(l.name(), "robot1");
  EXPECT_EQ(l.message(), "CH4 HIGH");
  EXPECT_EQ(l.timestamp().nanos(), 1);
  e.set_kind(v1::Event::MODE_CHANGE);
  EXPECT_EQ(RobotScene::log("robot1", e, 0).level(), ::foxglove::Log::INFO);
}

TEST(RobotScene, TheGasMapGoesOnAcrossARestartedRobotClockAndCleanAirIsBlue) {
  RobotScene s("robot1", Geometry{});
  s.onHello(sceneHello());
  for (int i = 0; i < 40; ++i) s.onTelemetry(sceneTelemetry(10.0 + i * 0.05, 0, 0.0));  // clean air
  // robot_client restarted: its clock counts from 0 again, the robot 2 m on.
  for (int i = 0; i < 40; ++i) s.onTelemetry(sceneTelemetry(i * 0.05, 2, 15.0));
  const auto g = s.grid("CH4", 0);
  ASSERT_TRUE(g.has_value());
  const auto at = [&](double x, double y) {
    const auto c = static_cast<std::size_t>((x - g->pose().position().x()) / g->cell_size().x());
    const auto r = static_cast<std::size_t>((y - g->pose().position().y()) / g->cell_size().y());
    return r * g->row_stride() + c * 8;
  };
  float before = 0, after = 0;
  std::memcpy(&before, g->data().data() + at(0, 0.3), 4);
  std::memcpy(&after, g->data().data() + at(2, 0.3), 4);
  EXPECT_NEAR(before, 0.0, 1e-3);
  EXPECT_NEAR(after, 15.0, 1e-3);  // mapped after the restart
  // Clean air (the channel's background, 0 here) is blue.
  const auto* cell = g->data().data() + at(0, 0.3);
  EXPECT_GT(static_cast<uint8_t>(cell[6]), static_cast<uint8_t>(cell[4]));
}

TEST(RobotScene, AMapTakenAwayLeavesEmptyMapEntities) {
  RobotScene s("robot1", Geometry{});
  SiteMap m;
  m.walls = {{{0, 0}, {4, 0}}};
  s.setMap(m);
  s.setMap(std::nullopt);
  const auto u = s.scene(0);
  bool walls = false;
  for (const auto& e : u.entities())
    if (e.id() == "map/walls") {
      walls = true;
      EXPECT_EQ(e.cubes_size(), 0);
    }
  EXPECT_TRUE(walls);  // sent empty: replaces the old walls in the client
}
