#include "shared/robot/awareness.hpp"

#include "shared/behavior/speed_strategy.hpp"
#include "shared/config/config_node.hpp"
#include "shared/fuzzy/fis_error.hpp"

namespace inspect::robot {

std::unique_ptr<behavior::HumanAwareness> makeAwareness(const config::RobotConfig& robot,
                                                        behavior::AwarenessConfig awareness,
                                                        std::vector<geometry::Segment> map,
                                                        const std::string& source) {
  awareness.robot_radius_m = robot.geometry.body_radius_m;
  try {
    return std::make_unique<behavior::HumanAwareness>(
        robot.ultrasonic, awareness, behavior::loadSpeedStrategy(awareness.speed_fis, awareness.speed),
        std::move(map));
  } catch (const fuzzy::FisError& e) {
    throw config::ConfigError(source + ": awareness.speed_fis: " + e.what());
  }
}

}  // namespace inspect::robot
