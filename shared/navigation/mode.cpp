#include "shared/navigation/mode.hpp"

namespace inspect::navigation {

const char* toString(Mode m) {
  switch (m) {
    case Mode::kGoToGoal: return "GO_TO_GOAL";
    case Mode::kAvoid: return "AVOID";
    case Mode::kFollowCw: return "FOLLOW_CW";
    case Mode::kFollowCcw: return "FOLLOW_CCW";
    case Mode::kAtGoal: return "AT_GOAL";
  }
  return "?";
}

const char* toString(FollowSide s) {
  switch (s) {
    case FollowSide::kNone: return "none";
    case FollowSide::kClockwise: return "cw";
    case FollowSide::kCounterClockwise: return "ccw";
  }
  return "?";
}

}  // namespace inspect::navigation
