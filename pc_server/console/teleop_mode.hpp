#pragma once
// `teleop [step|hold]`'s mode (docs/console.md, "Keyboard teleop"): the
// console parses it, the terminal's keyboard teleop runs it.
#include <string>

namespace inspect::server {

/// step: keys step the set-point, which stays until changed.
/// hold: a key drives at a fixed speed while its auto-repeats keep arriving (deadman).
enum class TeleopMode { kStep, kHold };

/// Parses a teleop mode word ("step", "hold"); false for any other.
inline bool parseTeleopMode(const std::string& word, TeleopMode& mode) {
  if (word == "step") mode = TeleopMode::kStep;
  else if (word == "hold") mode = TeleopMode::kHold;
  else return false;
  return true;
}

}  // namespace inspect::server
