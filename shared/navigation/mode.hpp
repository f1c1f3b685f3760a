#pragma once
// Discrete state of the navigation hybrid automaton (chapter 5.4.3, Fig 5.11).
#include <cstdint>

namespace inspect::navigation {

/// The automaton's modes; each runs one behaviour.
enum class Mode : uint8_t {
  kGoToGoal,    // go-to-goal (blended with avoid in SwitchingStyle::kBlend)
  kAvoid,       // obstacle avoidance: dangerously close, move away
  kFollowCw,    // boundary following, u_AO rotated by -pi/2: the robot goes clockwise round the obstacle
  kFollowCcw,   // boundary following, u_AO rotated by +pi/2: counter-clockwise round the obstacle
  kAtGoal,      // within epsilon of the goal (or no goal): stop
};
/// Upper-case name as in the docs ("GO_TO_GOAL", ...).
const char* toString(Mode m);

/// Which way round an obstacle the boundary is followed.
enum class FollowSide : uint8_t {
  kNone,              // no boundary has been followed yet
  kClockwise,         // obstacle on the robot's right
  kCounterClockwise,  // obstacle on the robot's left
};
/// Lower-case name ("none", "cw", "ccw").
const char* toString(FollowSide s);

/// The follow mode of a side (kGoToGoal for kNone).
inline Mode followMode(FollowSide s) {
  return s == FollowSide::kClockwise ? Mode::kFollowCw
         : s == FollowSide::kCounterClockwise ? Mode::kFollowCcw
                                              : Mode::kGoToGoal;
}

}  // namespace inspect::navigation
