#pragma once
// The simulated world: walls, closed obstacles, floor lines, the robot's start
// pose, scripted pedestrians and gas leaks, loaded from a YAML world file
// (docs/world-format.md).
#include <optional>
#include <string>
#include <vector>

#include "shared/behavior/social_force.hpp"
#include "shared/config/config_node.hpp"
#include "shared/control/diff_drive.hpp"
#include "shared/control/plant_model.hpp"
#include "shared/world/gas_spec.hpp"
#include "shared/geometry/polygon.hpp"
#include "shared/world/pedestrian_script.hpp"

namespace inspect::world {

using geometry::Polygon;
using geometry::Segment;
using geometry::Vec2;
using geometry::pointText;

/// World coordinates (walls, obstacles, people, gas sources) stay within
/// +-kMaxCoord_m, a sane box that also keeps float error small.
inline constexpr double kMaxCoord_m = 1000.0;

/// A painted line on the floor seen by the grayscale sensor.
struct FloorLine {
  Segment centre;
  double width_m = 0.025;
};

/// A named closed obstacle (box, pillar, L-shaped shelf ...).
struct Obstacle {
  std::string name;
  Polygon polygon;
};

/// Everything in a world file.
struct World {
  std::string name;
  std::string description;
  std::string source_file;  // file the world was loaded from (for error messages)
  control::Pose2 start;
  std::vector<Segment> walls;  // thin walls (two-sided segments)
  std::vector<Obstacle> obstacles;
  std::vector<FloorLine> floor_lines;
  std::vector<PedestrianScript> pedestrians;  // moved by the social force model
  behavior::SocialForceParams social_force;   // the `social_force` section (defaults when absent)
  GasSpec gas;                                // the `gas` section: leaks, dispersion, sensor faults
  std::optional<control::PlantModel> plant;   // the `plant` section: the robot's true hub motors
};

/// An axis-aligned box, lo <= hi.
struct Bounds {
  Vec2 lo;
  Vec2 hi;
};

/// Distance from p to the nearest wall or obstacle edge; 0 when p is inside
/// an obstacle; infinity in a world with nothing solid.
double clearance(const World& w, Vec2 p);
/// Distance to the first wall or obstacle edge along the ray from origin at
/// world angle yaw_rad, or nullopt when nothing is hit within max_range_m.
std::optional<double> castRay(const World& w, Vec2 origin, double yaw_rad, double max_range_m);
/// Every wall and obstacle edge, as the social force model sees them (corners
/// where edges meet marked as joined).
std::vector<behavior::WallSegment> solidEdges(const World& w);
/// Bounding box of every wall and obstacle; nullopt when there is nothing solid.
std::optional<Bounds> solidBounds(const World& w);
/// True when p lies on a floor line (within half its width of the centre line).
bool onFloorLine(const World& w, Vec2 p);

/// Reads a world from a parsed file; throws config::ConfigError naming file, key and reason.
World loadWorld(const config::ConfigNode& root);
/// Loads a world file and rejects unknown keys.
World loadWorldFile(const std::string& path);
/// Reads a world from YAML text (tests, tools); `name` stands in for the file
/// name in error messages. Unknown keys are errors, as for files.
World loadWorldText(const std::string& yaml, const std::string& name);
/// Throws ConfigError (naming the world file and `start`) when a robot of
/// body_radius_m at the start pose would overlap a wall or obstacle.
void checkStartPose(const World& world, double body_radius_m);

}  // namespace inspect::world
