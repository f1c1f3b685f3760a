#pragma once
// The decision core's safety parameters (config/client.yaml `safety:`):
// timeouts of the latches, the obstacle slow-down while tracking, the
// route's stall limit, and what a gas HIGH alarm does to a route.
#include <optional>
#include <string_view>

namespace inspect::robot {

/// Reaction to a gas HIGH (A2) alarm while on a route (goto/route/inspect; docs/gas.md).
enum class GasReaction {
  kContinue,  ///< the route goes on (the alarm is announced)
  kStop,      ///< stop and hold; `resume` goes on, `stop` ends the route
  kRetreat,   ///< back along the route's points reached so far to its start
};

/// "continue", "stop", "retreat".
const char* gasReactionName(GasReaction r);
/// The reaction of a config or command-line word; nullopt for another word.
std::optional<GasReaction> gasReactionOf(std::string_view name);

struct SafetyParams {
  double link_timeout_s = 0.25;
  double command_timeout_s = 0.3;
  double sensor_timeout_s = 0.1;
  // Tracking only: the nearest front-sonar range scales the speed down from
  // obstacle_slow_m to a stop at obstacle_stop_m (like the MCU's own
  // anti-collision stop), whatever the obstacle; people get Eq 9 as well.
  double obstacle_stop_m = 0.35;
  double obstacle_slow_m = 0.9;
  // Navigation: a goal whose distance has not shrunk by 0.1 m in this much
  // time allowed to move (time scaled by the Eq 9 factor, so waiting for
  // people does not count) is given up: Ack FAILED, IDLE.
  double nav_stall_s = 120.0;
  GasReaction gas_reaction = GasReaction::kStop;
};

}  // namespace inspect::robot
