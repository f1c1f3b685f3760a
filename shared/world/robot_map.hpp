#pragma once
// The robot's static map for people tracking: the walls and obstacle edges of
// a world file, in the robot's odometry frame.
#include <vector>

#include "shared/geometry/segment.hpp"
#include "shared/world/world.hpp"

namespace inspect::world {

/// Every wall segment and obstacle edge of `w` (solidEdges), moved from
/// the world frame into the odometry frame of a robot started at `w.start`
/// (origin and x axis = the start pose), ready for behavior::HumanAwareness.
std::vector<Segment> mapFromWorld(const World& w);

}  // namespace inspect::world
