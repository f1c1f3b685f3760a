#pragma once
// A scripted pedestrian from a world file's `pedestrians:` list: who, how big,
// how fast, when, and the route walked (docs/world-format.md).
#include <cstddef>
#include <string>
#include <vector>

#include "shared/config/config_node.hpp"
#include "shared/geometry/vec2.hpp"

namespace inspect::world {

using geometry::Vec2;

struct World;

/// A stop of `duration_s` on reaching waypoint `at` (0 = the start point).
struct PedestrianPause {
  std::size_t at = 0;
  double duration_s = 0.0;
};

/// What a world file says about one pedestrian.
struct PedestrianScript {
  std::string id;              // unique in the world; 1-64 letters, digits, '_', '-', '.'
  double radius_m = 0.25;      // body circle (social force and ultrasonic)
  double speed_m_s = 0.5;      // desired speed v0 (the paper's experiments: 0.5 m/s)
  double start_s = 0.0;        // sim time at which it appears at route.front() and starts walking
  std::vector<Vec2> route;     // waypoints; the first is the start position
  std::vector<PedestrianPause> pauses;
  bool loop = false;           // after the last waypoint walk to the first again, forever
  double arrive_m = 0.3;       // a waypoint counts as reached within this distance
  bool notices_robot = true;   // false: keeps their line past the robot; only body contact stops them
};

/// Reads root's `pedestrians` list (walls and obstacles of `world` already
/// loaded: route points must be clear of them). Throws config::ConfigError
/// naming file, key and reason.
std::vector<PedestrianScript> readPedestrianScripts(const config::ConfigNode& root, const World& world);

}  // namespace inspect::world
