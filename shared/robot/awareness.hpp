#pragma once
// The one place the robot's people awareness is assembled (robot_client and
// the scenario runner both): the robot's sonars and body radius, the
// behaviour config, its speed rule base (Eq 9), and the static map whose
// walls people tracking ignores.
#include <memory>
#include <string>
#include <vector>

#include "shared/behavior/human_awareness.hpp"
#include "shared/config/robot_config.hpp"

namespace inspect::robot {

/// Throws config::ConfigError naming `source` (the behaviour config's file)
/// when the rule base of `awareness.speed_fis` cannot be read.
std::unique_ptr<behavior::HumanAwareness> makeAwareness(const config::RobotConfig& robot,
                                                        behavior::AwarenessConfig awareness,
                                                        std::vector<geometry::Segment> map,
                                                        const std::string& source);

}  // namespace inspect::robot
