#include "tests/support/paths.hpp"

namespace inspect::test {

const std::string& sourceDir() {
  static const std::string dir = INSPECT_SOURCE_DIR;
  return dir;
}

const std::string& binDir() {
  static const std::string dir = INSPECT_BIN_DIR;
  return dir;
}

std::string srcPath(const std::string& rel) { return sourceDir() + "/" + rel; }
std::string binPath(const std::string& prog) { return binDir() + "/" + prog; }
std::string firmwareImage() { return INSPECT_FIRMWARE_IMAGE; }

}  // namespace inspect::test
