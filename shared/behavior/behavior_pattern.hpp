#pragma once
// Behaviour pattern of the interfering body (a person) relative to the robot
// (paper section 3.2.2, Figure 5). The numeric values are the crisp input
// B_j of the fuzzy speed strategy (config/fuzzy/speed_strategy.fis, Table 1):
// BS = 1, BE = 2, BL = 3, BF = 4.
#include <string_view>

namespace inspect::behavior {

/// Pattern of a person relative to the robot; kNone = no interfering body.
enum class Pattern {
  kNone = 0,          ///< nobody to react to
  kCrossing = 1,      ///< BS: crosses the robot's path in front (aisle intersection)
  kEncountering = 2,  ///< BE: meets the robot face to face, laterally offset
  kLeading = 3,       ///< BL: directly ahead, moving in the robot's direction
  kConfronting = 4,   ///< BF: directly ahead, moving towards the robot
};

/// Lower-case name ("none", "crossing", ...); "unknown" for values outside the enum.
constexpr std::string_view toString(Pattern p) noexcept {
  switch (p) {
    case Pattern::kNone: return "none";
    case Pattern::kCrossing: return "crossing";
    case Pattern::kEncountering: return "encountering";
    case Pattern::kLeading: return "leading";
    case Pattern::kConfronting: return "confronting";
  }
  return "unknown";
}

}  // namespace inspect::behavior
