#pragma once
// One robot's messages turned into what its 3-D view shows, for the live
// Foxglove bridge and the recorder alike (docs/foxglove.md, docs/mcap.md):
// the RobotScene (body, sonar, people, route, alarms, transforms, grids, log
// lines) following the robot's Hello, telemetry, commands and events; the
// site map it is in; and the camera's people stamped with the picture they
// were seen in. Each owner publishes at its own rates; what is published is
// built here once. Not thread-safe (its owner's lock).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "pc_server/scene/camera_people.hpp"
#include "pc_server/scene/robot_scene.hpp"
#include "pc_server/scene/site_maps.hpp"

namespace inspect::server::scene {

class SceneFeed {
 public:
  SceneFeed(std::string robot, Geometry geometry) : scene_(std::move(robot), geometry) {}

  /// A message to (inbound false: the commands) or from the robot.
  void onEnvelope(const v1::Envelope& env, bool inbound);
  void onHello(const v1::Hello& hello) { scene_.onHello(hello); }
  /// A head's camera picture published at `ns` (capture_server_us: its capture on the server's clock, 0 = none).
  void onAccessUnit(const video::Frame& f, uint64_t capture_server_us, uint64_t ns,
                    v1::CameraHead head = v1::PTZ_HEAD) {
    clock(head).onAccessUnit(f, capture_server_us, ns);
  }
  /// The people in the head's picture this telemetry is the first to report
  /// (Telemetry.perception, .wide_perception), with that picture's timestamp
  /// on the head's camera channel; nullopt otherwise.
  /// link_offset_us: receive - send of the telemetry's envelope.
  std::optional<std::pair<uint64_t, ::foxglove::ImageAnnotations>> cameraPeople(const v1::Telemetry& t,
                                                                                 int64_t link_offset_us,
                                                                                 v1::CameraHead head = v1::PTZ_HEAD);
  /// Takes the robot's site map from `maps` when it changed since the last call.
  void followMap(SiteMaps& maps, const std::string& robot);

  const RobotScene& scene() const { return scene_; }

 private:
  RobotScene scene_;
  CameraPeopleClock& clock(v1::CameraHead head) { return head == v1::WIDE_HEAD ? wide_clock_ : people_clock_; }
  CameraPeopleClock people_clock_, wide_clock_;
  uint64_t map_version_ = 0;
};

}  // namespace inspect::server::scene
