#pragma once
// The world file's types (shared/world) under the simulator's own names:
// the simulator reads and simulates worlds, the world format is a library
// below it (docs/architecture.md).
#include "shared/world/gas_spec.hpp"
#include "shared/geometry/circle.hpp"
#include "shared/geometry/polygon.hpp"
#include "shared/world/pedestrian_script.hpp"
#include "shared/world/world.hpp"

namespace inspect::sim {

using world::Bounds;
using world::castRay;
using world::checkStartPose;
using world::clearance;
using world::FloorLine;
using world::GasFaultKind;
using world::GasFault;
using world::GasSource;
using world::GasSpec;
using world::kGasMaxPreRunNoVentilation_s;
using world::kMaxCoord_m;
using world::loadWorld;
using world::loadWorldFile;
using world::loadWorldText;
using world::Obstacle;
using world::onFloorLine;
using world::PedestrianPause;
using world::PedestrianScript;
using geometry::Circle;
using geometry::Polygon;
using world::readGasSpec;
using world::readPedestrianScripts;
using geometry::Segment;
using world::solidBounds;
using world::solidEdges;
using geometry::Vec2;
using world::World;
using geometry::pointText;

}  // namespace inspect::sim
