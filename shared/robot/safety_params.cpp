#include "shared/robot/safety_params.hpp"

namespace inspect::robot {

const char* gasReactionName(GasReaction r) {
  switch (r) {
    case GasReaction::kContinue: return "continue";
    case GasReaction::kStop: return "stop";
    case GasReaction::kRetreat: return "retreat";
  }
  return "stop";
}

std::optional<GasReaction> gasReactionOf(std::string_view name) {
  for (GasReaction r : {GasReaction::kContinue, GasReaction::kStop, GasReaction::kRetreat})
    if (name == gasReactionName(r)) return r;
  return std::nullopt;
}

}  // namespace inspect::robot
