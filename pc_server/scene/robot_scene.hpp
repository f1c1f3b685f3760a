#pragma once
// One robot's 3-D scene for Foxglove (docs/foxglove.md, "The scene"): what the
// server knows of the robot - its Hello, telemetry, the routes sent to it, its
// events and the site map - turned into foxglove.FrameTransforms,
// foxglove.SceneUpdate, one foxglove.Grid per gas channel and foxglove.Log.
// The live bridge and the recorder both use it, so a recorded run shows the
// same view as the live one. Pure: times come in as arguments, no I/O.
//
// Frames: "map" (the site map's world frame) -> "<robot>/odom" (the robot's
// odometry origin: the map's start pose) -> "<robot>/base_link" (the telemetry
// pose) -> "<robot>/sonar_fl|fr|l|r" and "<robot>/camera_mount" (pan) ->
// "<robot>/camera" (tilt; the optical frame: +z ahead, +x right, +y down).
#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "foxglove/CompressedVideo.pb.h"
#include "foxglove/FrameTransforms.pb.h"
#include "foxglove/Grid.pb.h"
#include "foxglove/Log.pb.h"
#include "foxglove/SceneUpdate.pb.h"
#include "inspect_robot/v1/link.pb.h"
#include "shared/config/robot_config.hpp"
#include "shared/gas/live_map.hpp"
#include "shared/geometry/segment.hpp"
#include "shared/video/rtp_h264.hpp"

namespace inspect::world {
struct World;
}

namespace inspect::server::scene {

/// The robot's body and sensors as drawn (defaults: config/robot.yaml's).
struct Geometry {
  double body_radius_m = config::RobotGeometry{}.body_radius_m;
  double body_height_m = 0.45;
  std::array<config::UltrasonicMount, 4> sonars = config::UltrasonicConfig{}.mounts;
  double sonar_beam_rad = config::UltrasonicConfig{}.beam_width_rad;
  double sonar_max_m = config::UltrasonicConfig{}.max_range_m;
  double sonar_z_m = 0.25;
  double camera_x_m = config::CameraMount{}.x_m, camera_y_m = config::CameraMount{}.y_m,
         camera_z_m = config::CameraMount{}.z_m;
  // The wide head's lens (robot.yaml wide_camera; its frame "<robot>/camera_wide").
  bool wide_camera = false;  // the robot config has one (its frame is published only then)
  double wide_camera_x_m = 0.24, wide_camera_y_m = 0.0, wide_camera_z_m = 0.55, wide_camera_tilt_deg = 0.0;
};
Geometry geometryOf(const config::RobotConfig& c);

/// The site map drawn in the "map" frame.
struct SiteMap {
  std::string name;
  std::vector<geometry::Segment> walls;      // thin walls
  std::vector<geometry::Segment> obstacles;  // obstacle edges
  std::vector<geometry::Segment> floor_lines;
  double start_x_m = 0, start_y_m = 0, start_theta_rad = 0;  // the odometry origin in the map
};
SiteMap siteMapOf(const world::World& w);

/// The sonar names, in telemetry order (front-left, front-right, left, right).
inline constexpr std::array<const char*, 4> kSonarNames{"sonar_fl", "sonar_fr", "sonar_l", "sonar_r"};

class RobotScene {
 public:
  RobotScene(std::string robot_id, Geometry geometry);

  const std::string& robot() const { return robot_; }
  /// "<robot>/<leaf>".
  std::string frame(const std::string& leaf) const { return robot_ + "/" + leaf; }

  void setMap(std::optional<SiteMap> map);
  bool hasMap() const { return map_.has_value(); }
  void onHello(const v1::Hello& hello);
  /// A telemetry message (its robot time paces the gas map).
  void onTelemetry(const v1::Telemetry& t);
  /// A command sent to the robot (routes and goals are drawn).
  void onCommand(const v1::Command& c);
  /// A robot event (alarm markers).
  void onEvent(const v1::Event& e);
  bool hasTelemetry() const { return have_telemetry_; }

  ::foxglove::FrameTransforms transforms(uint64_t ns) const;
  ::foxglove::SceneUpdate scene(uint64_t ns) const;
  /// Gas channel names with a grid so far (Hello order).
  std::vector<std::string> gridChannels() const;
  /// The live concentration grid of a channel (nullopt: no data yet).
  std::optional<::foxglove::Grid> grid(const std::string& channel, uint64_t ns) const;
  /// A camera access unit as Foxglove's video message (frame "<robot>/camera",
  /// or "<robot>/camera_wide" for the wide head; the Annex B bytes as
  /// received: nothing re-encoded).
  static ::foxglove::CompressedVideo cameraFrame(const std::string& robot, const video::Frame& f, uint64_t ns,
                                                 v1::CameraHead head = v1::PTZ_HEAD);
  /// A robot event as a log line (level from its kind).
  static ::foxglove::Log log(const std::string& robot, const v1::Event& e, uint64_t ns);

 private:
  // The parts of scene(), each its own entities.
  /// The site map, in the world frame: always sent (empty without a map).
  void addMap(::foxglove::SceneUpdate& u, uint64_t ns) const;
  void addBody(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const;
  void addSonars(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const;
  void addPeople(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const;
  void addCameraPeople(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const;
  void addRoute(::foxglove::SceneUpdate& u, const v1::Telemetry& t, uint64_t ns) const;
  void addAlarms(::foxglove::SceneUpdate& u, uint64_t ns) const;
  struct Channel {
    v1::GasChannelInfo info;
    gas::LiveConcentrationMap map;
    std::deque<gas::GasSample> window;  // the last second of samples (lag compensation)
    double last_sample_s = -1;
  };
  struct Alarm {
    v1::GasAlarm alarm;
    bool active = true;
  };
  void addGas(const v1::Telemetry& t, double t_s);

  std::string robot_;
  Geometry g_;
  std::optional<SiteMap> map_;
  v1::Hello hello_;
  bool have_telemetry_ = false;
  v1::Telemetry last_;
  std::vector<v1::Point2> route_;
  std::string route_name_;
  std::vector<Channel> channels_;
  std::map<uint64_t, Alarm> alarms_;  // alarm id -> latest transition (the newest kMaxAlarms)
  static constexpr std::size_t kMaxAlarms = 200;
};

}  // namespace inspect::server::scene
