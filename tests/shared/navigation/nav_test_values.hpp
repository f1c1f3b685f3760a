#pragma once
// Values the navigation tests share: pi, a missing reading (NaN) and the
// default ultrasonic geometry of config::UltrasonicConfig.
#include <limits>
#include <numbers>

#include "shared/config/robot_config.hpp"

namespace inspect::test {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline const config::UltrasonicConfig kSonar{};

}  // namespace inspect::test
