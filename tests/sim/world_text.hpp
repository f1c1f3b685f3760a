#pragma once
// World files from YAML text for tests: the world, or the error it gives.
#include <string>

#include "sim/world.hpp"

namespace inspect::test {

/// The ConfigError message of loading `yaml` as a world named `name`; "" when it loads.
inline std::string worldError(const std::string& yaml, const std::string& name) {
  try {
    (void)sim::loadWorldText(yaml, name);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace inspect::test
