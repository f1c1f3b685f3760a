# How the project's tests are built and registered (docs/testing.md). Every
# test program and every ctest test goes through these functions, so that
# each one has a label, a TIMEOUT and the scheduling properties that let
# `ctest -j` run the suite in parallel without starving the real-time tests.
#
# Labels (the first argument of LABELS is the test's kind):
#   unit      one test program in-process (sockets, a pty or a child program
#             at most). `scripts/test.sh --quick` runs these.
#   stack     the real programs together (mcu_sim, robot_client, pc_server) in
#             real time or a few times faster.
#   long      not in CI: the long forms of measurements (by hand or -L long).
#   bench     the smoke runs of the benchmarks (figures printed, not judged):
#             a stack slot each, like a stack test; SERIAL for the ones
#             that take a core (QEMU, the CPU-bound measurements).
#   package   the Debian packages installed into a clean root (root, mirror).
#   fuzz, sanitize   the second stage of scripts/test.sh (build-asan/).
# Further labels name an area (faults, link, load, record ...).
#
# Scheduling: scripts/test.sh runs the unit tests first (ctest -j <2 x cores>),
# then the stack and bench tests with the resource spec
# tests/ctest_resources.json, which has 4 `stack` slots: a stack test takes
# one (RESOURCE_GROUPS stack:1), so at most four run at once (they mostly
# wait on real time: 53-61 % of the 2 cores busy with three or four). They never
# share the machine with CPU-bound tests: on this 2-core virtual machine two
# busy cores stall every process for 100-250 ms whatever its priority (nice,
# SCHED_IDLE: measured, docs/testing.md), and a robot takes that for a dead
# sensor line. LOCK names a RESOURCE_LOCK: tests holding the same lock never
# overlap (`cores`: the tuning host's optimiser takes both cores for seconds,
# and the tracking comparison needs them free to hold its band of link
# latency). SLOTS n: a stack or bench test that takes n of the 4 slots (QEMU's
# firmware runs take 3: beside one other stack test they keep their figures,
# beside two they starved). SERIAL
# (RUN_SERIAL) is for tests that measure latencies or saturate the machine on
# purpose. COST (expected seconds) starts the long tests first on a clean
# tree, where ctest has no timings of its own yet. Without the resource spec
# (plain `ctest -j N`) the stack tests are limited by -j and the locks only.

# The test programs' own code is compiled without optimisation (-O0); the
# libraries it tests keep the build type's. Under the sanitizers it halved the
# test programs' compile time (clang 14); with g++ 12 -O0 against -O1 took
# server_tests' unit from 54 s to 35 s, and the test programs' code is a
# third of the build's compile time. What they time is the libraries' code
# and the real programs'.
set(INSPECT_TEST_OPT "-O0" CACHE STRING "Optimisation of the test programs' own code")
# libFuzzer's coverage instrumentation (INSPECT_FUZZ) only serves code a
# harness runs: not the test programs' own.
set(INSPECT_TEST_COMPILE_OPTIONS ${INSPECT_TEST_OPT})
if(INSPECT_FUZZ)
  list(APPEND INSPECT_TEST_COMPILE_OPTIONS -fno-sanitize=fuzzer-no-link)
endif()
# Their precompiled header, made with these options (cmake/InspectPch.cmake).
inspect_test_pch_target()

# Paths to the source tree and the programs, for every test program
# (tests/support/paths.hpp); only paths.cpp sees the absolute paths.
add_library(inspect_test_paths STATIC ${PROJECT_SOURCE_DIR}/tests/support/paths.cpp)
target_include_directories(inspect_test_paths PUBLIC ${PROJECT_SOURCE_DIR})
target_compile_definitions(inspect_test_paths PRIVATE INSPECT_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}"
                                                      INSPECT_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                                      INSPECT_FIRMWARE_IMAGE="${CMAKE_BINARY_DIR}/tests/firmware/mcu/inspect-mcu-qemu.elf")

# Child processes, temp dirs, the three programs wired together, the ground
# truth reader, the UDP relay, test certificates, an MQTT broker (tests/support).
add_library(inspect_test_support STATIC
  ${PROJECT_SOURCE_DIR}/tests/support/process.cpp
  ${PROJECT_SOURCE_DIR}/tests/support/stack.cpp
  ${PROJECT_SOURCE_DIR}/tests/support/mosquitto_broker.cpp
  ${PROJECT_SOURCE_DIR}/tests/support/sparkplug_host.cpp
  ${PROJECT_SOURCE_DIR}/tests/support/udp_relay.cpp)
target_link_libraries(inspect_test_support PUBLIC inspect_test_paths Threads::Threads)
target_compile_options(inspect_test_support PRIVATE ${INSPECT_TEST_COMPILE_OPTIONS})

# A real PostgreSQL server (tests/support/postgres_server.hpp): the fixture
# `postgres` below starts one for the whole ctest run; tests that use it
# take INSPECT_POSTGRES_TEST_PROPERTIES (the fixture and the file naming it).
if(NOT INSPECT_ROBOT_ONLY)
  add_library(inspect_test_postgres STATIC ${PROJECT_SOURCE_DIR}/tests/support/postgres_server.cpp
    ${PROJECT_SOURCE_DIR}/tests/support/sql_query.cpp)
  target_link_libraries(inspect_test_postgres PUBLIC inspect_test_paths inspect_catalog PkgConfig::LIBPQ)
  target_compile_options(inspect_test_postgres PRIVATE ${INSPECT_TEST_COMPILE_OPTIONS})
  set(INSPECT_POSTGRES_FILE ${CMAKE_BINARY_DIR}/Testing/postgres-dir)
  set(INSPECT_POSTGRES_TEST_PROPERTIES FIXTURES_REQUIRED postgres ENVIRONMENT INSPECT_TEST_PG_FILE=${INSPECT_POSTGRES_FILE})
endif()

# The one fake robot (tests/support/fake_robot): its messages, the fleet robot
# (asynchronous, many per io_context); the scripted robot is header-only.
add_library(inspect_fake_robot STATIC
  ${PROJECT_SOURCE_DIR}/tests/support/fake_robot/robot_messages.cpp
  ${PROJECT_SOURCE_DIR}/tests/support/fake_robot/fleet_robot.cpp)
target_compile_options(inspect_fake_robot PRIVATE ${INSPECT_TEST_COMPILE_OPTIONS})
target_link_libraries(inspect_fake_robot PUBLIC inspect_test_support inspect_shared inspect_tls inspect_proto
                      OpenSSL::SSL Boost::headers Threads::Threads)


# inspect_test_program(<name> SOURCES <files...> [LIBS <libs...>] [PROGRAMS <targets...>] [NO_UNITY])
# A test program: its sources (one translation unit unless NO_UNITY), the
# libraries it links, the support library and gtest_main, and the programs
# it starts (built before it).
function(inspect_test_program name)
  cmake_parse_arguments(A "NO_UNITY;NO_GTEST_MAIN" "" "SOURCES;LIBS;PROGRAMS" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_LIBS} inspect_test_support)
  if(NOT A_NO_GTEST_MAIN)
    target_link_libraries(${name} PRIVATE GTest::gtest_main)
  endif()
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_options(${name} PRIVATE ${INSPECT_TEST_COMPILE_OPTIONS})
  if(INSPECT_SANITIZE)
    # For the few checks of speed that an instrumented build cannot meet.
    target_compile_definitions(${name} PRIVATE INSPECT_SANITIZED=1)
  endif()
  foreach(prog IN LISTS A_PROGRAMS)
    if(TARGET ${prog})
      add_dependencies(${name} ${prog})
    endif()
  endforeach()
  if(NOT A_NO_UNITY)
    inspect_unity(${name})
  endif()
endfunction()

# The ctest properties of a test kind, into <out>: TIMEOUT and the scheduling
# (not LABELS, which may be a list), from the parsed arguments A_* of the
# caller (inspect_gtests, inspect_test); _kind is the first label.
macro(_inspect_test_properties out)
  if(NOT A_LABELS)
    message(FATAL_ERROR "a test needs LABELS (unit, stack, long, bench, ...): tests/InspectTest.cmake")
  endif()
  if(NOT A_TIMEOUT)
    message(FATAL_ERROR "a test needs a TIMEOUT: tests/InspectTest.cmake")
  endif()
  list(GET A_LABELS 0 _kind)
  if(NOT _kind MATCHES "^(unit|stack|bench|package|long|sanitize)$")
    message(FATAL_ERROR "a test's first label is its kind: unit, stack, bench, package or long, not '${_kind}'")
  endif()
  set(${out} TIMEOUT ${A_TIMEOUT})
  if(A_SERIAL AND A_SLOTS)
    message(FATAL_ERROR "a test is SERIAL or takes SLOTS, not both")
  endif()
  if(A_SERIAL)
    list(APPEND ${out} RUN_SERIAL TRUE)
  elseif(_kind MATCHES "^(stack|bench)$")
    if(NOT A_SLOTS)
      set(A_SLOTS 1)
    endif()
    list(APPEND ${out} RESOURCE_GROUPS stack:${A_SLOTS})
  endif()
  if(A_LOCK)
    list(APPEND ${out} RESOURCE_LOCK ${A_LOCK})
  endif()
  if(A_COST)
    list(APPEND ${out} COST ${A_COST})
  endif()
  list(APPEND ${out} ${A_PROPERTIES})
endmacro()

# inspect_gtests(<program> LABELS <kind> TIMEOUT <s> [SERIAL | SLOTS n] [LOCK name] [COST s]
#                [FILTER <gtest filter>] [SANITIZE [SANITIZE_SKIP <gtest patterns>]]
#                [PROPERTIES <ctest properties...>])
# One ctest test per gtest test of <program> (gtest_discover_tests; its
# PROPERTIES cannot carry a list, hence one label). SANITIZE: the program is
# also part of the sanitizer stage. The sanitizer build (INSPECT_FUZZ, see
# tests/fuzz/CMakeLists.txt) builds those programs in its target
# sanitize_tests and runs each call's tests as one ctest test, one process,
# labelled `sanitize`: a process start under ASan costs up to 0.5 s (the video
# libraries' initialisation), 0.28 s a test on average, and LeakSanitizer then
# checks the whole run at its exit. The other programs can be built and run
# there by hand. SANITIZE_SKIP: tests of the call left out of the sanitizer
# stage only (':'-separated gtest patterns): the long numeric sweeps and cost
# measurements, whose code the stage's other tests run on fewer points; the
# g++ build runs them all.
function(inspect_gtests program)
  cmake_parse_arguments(A "SERIAL;SANITIZE" "TIMEOUT;LOCK;COST;SLOTS;FILTER;SANITIZE_SKIP" "LABELS;PROPERTIES" ${ARGN})
  list(LENGTH A_LABELS n)
  if(NOT n EQUAL 1)
    message(FATAL_ERROR "inspect_gtests(${program}): one label (the kind), got '${A_LABELS}'")
  endif()
  if(INSPECT_FUZZ)
    if(NOT A_SANITIZE)
      return()
    endif()
    set_property(GLOBAL APPEND PROPERTY INSPECT_SANITIZE_PROGRAMS ${program})
    get_property(calls GLOBAL PROPERTY INSPECT_SANITIZE_CALLS_${program})
    math(EXPR calls "${calls} + 1")
    set_property(GLOBAL PROPERTY INSPECT_SANITIZE_CALLS_${program} ${calls})
    set(name ${program})
    if(calls GREATER 1)
      set(name ${program}_${calls})
    endif()
    if(A_SANITIZE_SKIP)
      # gtest's filter is POSITIVE[-NEGATIVE]: one '-', its patterns ':'-separated.
      if(A_FILTER MATCHES "-")
        string(APPEND A_FILTER ":${A_SANITIZE_SKIP}")
      else()
        string(APPEND A_FILTER "-${A_SANITIZE_SKIP}")
      endif()
    endif()
    set(filter)
    if(A_FILTER)
      set(filter "--gtest_filter=${A_FILTER}")
    endif()
    add_test(NAME ${name} COMMAND ${program} ${filter} WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    set(A_LABELS sanitize)
    set(A_TIMEOUT 900)  # the whole program
    if(NOT A_COST)
      set(A_COST 60)  # before the fuzz harnesses' 20 s runs
    endif()
    _inspect_test_properties(props)
    list(REMOVE_ITEM props RESOURCE_GROUPS stack:1)
    set_tests_properties(${name} PROPERTIES LABELS sanitize ${props})
    return()
  endif()
  _inspect_test_properties(props)
  if(A_LABELS STREQUAL "unit")
    # One ctest test per gtest suite (cmake/GTestSuites.cmake says why); the
    # suites of a program's second call (another FILTER) are named <suite>_2.
    get_property(calls GLOBAL PROPERTY INSPECT_SUITE_CALLS_${program})
    math(EXPR calls "${calls} + 1")
    set_property(GLOBAL PROPERTY INSPECT_SUITE_CALLS_${program} ${calls})
    set(ctest_file ${CMAKE_CURRENT_BINARY_DIR}/${program}_suites_${calls}.cmake)
    list(REMOVE_AT props 0 1)  # TIMEOUT <s>: the script's, by the suite's size
    list(PREPEND props LABELS unit)
    add_custom_command(TARGET ${program} POST_BUILD
      COMMAND ${CMAKE_COMMAND} -D PROGRAM=$<TARGET_FILE:${program}> -D CTEST_FILE=${ctest_file}
              -D "EMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -D "FILTER=${A_FILTER}" -D SUFFIX=$<$<VERSION_GREATER:${calls},1>:_${calls}> -D WORKING_DIR=${CMAKE_CURRENT_BINARY_DIR} -D TIMEOUT=${A_TIMEOUT}
              "-DPROPERTIES=${props}" -P ${PROJECT_SOURCE_DIR}/cmake/GTestSuites.cmake
      BYPRODUCTS ${ctest_file} VERBATIM)
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${ctest_file})
    return()
  endif()
  set(filter)
  if(A_FILTER)
    set(filter TEST_FILTER "${A_FILTER}")
  endif()
  gtest_discover_tests(${program} DISCOVERY_TIMEOUT 30 ${filter} PROPERTIES LABELS ${A_LABELS} ${props})
endfunction()

# inspect_test(NAME <name> COMMAND <command...> LABELS <kind> [<area>...] TIMEOUT <s>
#              [SERIAL | SLOTS n] [LOCK name] [COST s] [WORKING_DIRECTORY dir]
#              [FIXTURES_REQUIRED <fixture>...] [PROPERTIES <single-valued ctest properties...>])
# One ctest test running a command (a program of the build with arguments, a script).
function(inspect_test)
  cmake_parse_arguments(A "SERIAL" "NAME;TIMEOUT;LOCK;COST;SLOTS;WORKING_DIRECTORY"
                        "COMMAND;LABELS;FIXTURES_REQUIRED;PROPERTIES" ${ARGN})
  if(INSPECT_FUZZ)
    return()  # the sanitizer build runs the SANITIZE programs and the fuzz harnesses only
  endif()
  _inspect_test_properties(props)
  set(cmd ${A_COMMAND})
  list(GET A_COMMAND 0 first)
  if(TARGET ${first})
    list(SUBLIST A_COMMAND 1 -1 rest)
    set(cmd $<TARGET_FILE:${first}> ${rest})
  endif()
  set(wd)
  if(A_WORKING_DIRECTORY)
    set(wd WORKING_DIRECTORY ${A_WORKING_DIRECTORY})
  endif()
  add_test(NAME ${A_NAME} COMMAND ${cmd} ${wd})
  set_tests_properties(${A_NAME} PROPERTIES LABELS "${A_LABELS}" ${props})
  if(A_FIXTURES_REQUIRED)
    set_tests_properties(${A_NAME} PROPERTIES FIXTURES_REQUIRED "${A_FIXTURES_REQUIRED}")
  endif()
endfunction()
