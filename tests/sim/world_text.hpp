#pragma once
// World files from YAML text for tests: the world, or the error it gives.
#include <string>

#include "shared/world/world.hpp"

namespace inspect::test {

/// The world of `yaml` (a test's own world text; throws ConfigError when it is bad).
inline world::World worldOf(const std::string& yaml, const std::string& name = "world.yaml") {
  return world::loadWorldText(yaml, name);
}

/// The ConfigError message of loading `yaml` as a world named `name`; "" when it loads.
inline std::string worldError(const std::string& yaml, const std::string& name) {
  try {
    (void)world::loadWorldText(yaml, name);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace inspect::test
