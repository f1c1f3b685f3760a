# Precompiled headers (docs/testing.md "Build time"): the heavy headers that
# most translation units parse (the C++ library, Eigen, yaml-cpp, the
# generated link protobuf, OpenCV's core, Boost.Asio, nlohmann/json; for the
# test programs GoogleTest too) compiled once per build into a PCH that every
# target of that kind reuses (REUSE_FROM), instead of parsed again in each of
# ~150 translation units. Measured with -ftime-report: parsing was 45-55 % of
# a typical unit's time (scenario_suite.cpp 9.0 of 16.7 s).
#
# Two PCHs, one per set of compile options (a PCH is only used with the
# options it was made with): inspect_pch (the build type's optimisation: the
# libraries and programs) and inspect_test_pch (INSPECT_TEST_COMPILE_OPTIONS:
# the test programs' own code). A target whose options differ (the generated
# protobuf code's -w, the fuzz harnesses) is not given one.
#
# With ccache, cmake/ccache_launcher.sh sets the sloppiness ccache needs to
# cache a unit that uses a PCH and gives each PCH a checksum ccache hashes
# instead of it, so that another clone's units hit.
option(INSPECT_PCH "Precompiled headers for the libraries, programs and tests (faster builds)" ON)
# clang writes the time it was made into a PCH and refuses it when its headers
# are newer; ccache cannot cache a unit that uses such a PCH (ccache's manual,
# "Precompiled headers"): without this, a warm sanitizer build hit 18 of 94.
if(INSPECT_PCH AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  add_compile_options("SHELL:-Xclang -fno-pch-timestamp")
  # CMake's clang form names the header as `-Xclang -include -Xclang <path>`,
  # which ccache does not make relative to the tree, so a unit's hash held the
  # clone's folder. The driver's own `-include <header>` finds <header>.pch
  # beside it and uses it (as g++ does with .gch), and ccache reads that form.
  set(CMAKE_CXX_COMPILE_OPTIONS_USE_PCH -include <PCH_HEADER>)
endif()

set(INSPECT_PCH_HEADERS
  <algorithm> <array> <atomic> <chrono> <cmath> <condition_variable> <cstdint> <cstdio> <cstdlib> <cstring>
  <deque> <filesystem> <fstream> <functional> <iomanip> <iostream> <map> <memory> <mutex> <optional>
  <set> <sstream> <string> <string_view> <thread> <unordered_map> <utility> <variant> <vector>
  <Eigen/Core> <yaml-cpp/yaml.h> <nlohmann/json.hpp> <opencv2/core.hpp> <opencv2/imgproc.hpp>
  <boost/asio.hpp>
  [["inspect_robot/v1/link.pb.h"]])

# _inspect_pch_target(<name> <extra libraries...>): the PCH's own target (one
# empty unit); its include folders are those of the headers precompiled.
function(_inspect_pch_target name)
  set(anchor ${CMAKE_BINARY_DIR}/${name}_anchor.cpp)
  file(CONFIGURE OUTPUT ${anchor} CONTENT "// The precompiled header's own unit (cmake/InspectPch.cmake).\n")
  add_library(${name} STATIC ${anchor})
  # Include folders only: no compile definitions of their own (a PCH made
  # with a macro its user lacks is refused, by clang with an error).
  foreach(lib inspect_proto Eigen3::Eigen yaml-cpp OpenCV::Video ${ARGN})
    target_include_directories(${name} SYSTEM PRIVATE $<TARGET_PROPERTY:${lib},INTERFACE_INCLUDE_DIRECTORIES>)
  endforeach()
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  add_dependencies(${name} inspect_proto)
endfunction()

# The library and program PCH, once proto/ is known (the root CMakeLists.txt).
macro(inspect_pch_target)
  if(INSPECT_PCH)
    _inspect_pch_target(inspect_pch)
    target_precompile_headers(inspect_pch PRIVATE ${INSPECT_PCH_HEADERS})
  endif()
endmacro()

# The test programs' PCH, with their options (tests/InspectTest.cmake).
macro(inspect_test_pch_target)
  if(INSPECT_PCH)
    _inspect_pch_target(inspect_test_pch GTest::gtest GTest::gmock)
    # GoogleTest's own macros (GTEST_HAS_PTHREAD=1): its users have them.
    target_link_libraries(inspect_test_pch PRIVATE GTest::gtest GTest::gmock)
    target_compile_options(inspect_test_pch PRIVATE ${INSPECT_TEST_COMPILE_OPTIONS})
    target_precompile_headers(inspect_test_pch PRIVATE ${INSPECT_PCH_HEADERS} <gtest/gtest.h> <gmock/gmock.h>)
  endif()
endmacro()

# Every C++ library and program under <dir> reuses the PCH of its kind: the
# test programs' (their compile options hold INSPECT_TEST_OPT) or the
# others'. Not the generated protobuf code, the PCHs' own targets, the
# fuzz harnesses (tests/fuzz: libFuzzer's options) or a target with the
# property INSPECT_NO_PCH (other options of its own).
function(inspect_use_pch dir)
  if(NOT INSPECT_PCH)
    return()
  endif()
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    if(NOT type MATCHES "^(STATIC_LIBRARY|EXECUTABLE|OBJECT_LIBRARY)$" OR t MATCHES "^(inspect_proto|inspect_pch|inspect_test_pch)$"
       OR dir MATCHES "/tests/fuzz$")
      continue()
    endif()
    get_target_property(no_pch ${t} INSPECT_NO_PCH)
    if(no_pch)
      continue()
    endif()
    get_target_property(opts ${t} COMPILE_OPTIONS)
    get_target_property(libs ${t} LINK_LIBRARIES)
    set(pch inspect_pch)
    if(opts AND TARGET inspect_test_pch AND "${INSPECT_TEST_OPT}" IN_LIST opts)
      # A test program (GoogleTest's macros, as its PCH); the test support
      # libraries, with the same options but without GoogleTest, get none.
      if(NOT libs MATCHES "GTest::")
        continue()
      endif()
      set(pch inspect_test_pch)
    elseif(libs MATCHES "PkgConfig::GSTREAMER")
      continue()  # GStreamer's -pthread defines _REENTRANT; its one unit parses none of the PCH's headers
    endif()
    target_precompile_headers(${t} REUSE_FROM ${pch})
    # The PCH's include folders, for a unit that falls back to the headers' text.
    target_include_directories(${t} SYSTEM PRIVATE $<TARGET_PROPERTY:${pch},INCLUDE_DIRECTORIES>)
  endforeach()
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(d IN LISTS subdirs)
    inspect_use_pch(${d})
  endforeach()
endfunction()
