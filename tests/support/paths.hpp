#pragma once
// Where the tests find the source tree (configs, worlds, scripts) and the
// built programs. The absolute paths live in paths.cpp alone, compiled with
// them as definitions, so that every other test file compiles to the same
// object in any clone of the tree (compiler-cache hits across folders).
#include <string>

namespace inspect::test {

/// The source tree's root, e.g. /work/main.
const std::string& sourceDir();
/// The directory of the built programs (<build>/bin).
const std::string& binDir();
/// sourceDir() + "/" + rel.
std::string srcPath(const std::string& rel);
/// binDir() + "/" + prog.
std::string binPath(const std::string& prog);
/// The firmware's QEMU image that the test firmware_mcu_build builds (ctest
/// fixture `firmware_images`; tests/firmware/CMakeLists.txt).
std::string firmwareImage();

}  // namespace inspect::test
