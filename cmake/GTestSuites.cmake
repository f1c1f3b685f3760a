# Registers a unit-level gtest program's tests with ctest one test suite at a
# time: one ctest test, one process, per gtest suite (tests/InspectTest.cmake,
# inspect_gtests). Run after the program is built (a POST_BUILD step, as
# gtest_discover_tests does), with
#   -D PROGRAM=<the test program> -D CTEST_FILE=<the file ctest includes>
#   -D FILTER=<gtest filter or empty> -D WORKING_DIR=<dir> -D TIMEOUT=<s a test>
#   -D PROPERTIES=<name;value;... the ctest properties of every suite>
#   -D SUFFIX=<appended to every suite's test name, or empty>
#   -D EMULATOR=<what runs the program: CMAKE_CROSSCOMPILING_EMULATOR, or empty>
#
# Why: a unit test's own work is a few ms, but starting its program is not:
# server_tests links OpenCV's videoio and highgui and FFmpeg, 259 shared
# libraries, and the dynamic loader's symbol lookups take 0.24 s of every
# start (perf: 70 % in ld.so). One process per gtest test started 1209 of
# them; one per suite starts 206.
#
# A suite's ctest test is named after the suite (ExpectParse, Table/ExpectParseOk)
# and runs exactly the suite's tests that FILTER selects, named one by one.
# Its TIMEOUT is TIMEOUT a test, at most 600 s (or TIMEOUT when larger).
cmake_minimum_required(VERSION 3.25)

foreach(v PROGRAM CTEST_FILE WORKING_DIR TIMEOUT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "GTestSuites.cmake: -D ${v}=... is required")
  endif()
endforeach()

set(filter_arg)
if(FILTER)
  set(filter_arg "--gtest_filter=${FILTER}")
endif()
execute_process(COMMAND ${EMULATOR} "${PROGRAM}" --gtest_list_tests ${filter_arg}
                WORKING_DIRECTORY "${WORKING_DIR}" TIMEOUT 30
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "GTestSuites.cmake: ${PROGRAM} --gtest_list_tests failed (${rc}):\n${listing}\n${errors}")
endif()

# gtest's listing: "Suite.  # TypeParam = ..." lines, then "  Test  # GetParam() = ..."
# lines. The comments (parameter values may hold any character) go first.
string(REGEX REPLACE " *#[^\n]*" "" listing "${listing}")
string(REPLACE ";" "" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
set(suite)
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ ].*)\\.$")
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
    set(tests_${suite})
  elseif(line MATCHES "^  +([^ ]+)$" AND suite)
    list(APPEND tests_${suite} "${suite}.${CMAKE_MATCH_1}")
  endif()
endforeach()

set(runner "")
foreach(part IN LISTS EMULATOR ITEMS "${PROGRAM}")
  string(APPEND runner "[==[${part}]==] ")
endforeach()
set(script "")
foreach(suite IN LISTS suites)
  list(LENGTH tests_${suite} n)
  if(n EQUAL 0)
    continue()
  endif()
  list(JOIN tests_${suite} ":" names)
  math(EXPR timeout "${TIMEOUT} * ${n}")
  if(timeout GREATER 600)
    set(timeout 600)
  endif()
  if(timeout LESS TIMEOUT)
    set(timeout ${TIMEOUT})
  endif()
  set(name "${suite}${SUFFIX}")
  string(APPEND script "add_test([==[${name}]==] ${runner}[==[--gtest_filter=${names}]==])\n")
  string(APPEND script "set_tests_properties([==[${name}]==] PROPERTIES WORKING_DIRECTORY [==[${WORKING_DIR}]==]"
                       " TIMEOUT ${timeout}")
  set(props ${PROPERTIES})
  list(LENGTH props np)
  set(i 0)
  while(i LESS np)
    list(GET props ${i} pname)
    math(EXPR j "${i} + 1")
    list(GET props ${j} value)
    string(APPEND script " ${pname} [==[${value}]==]")
    math(EXPR i "${i} + 2")
  endwhile()
  string(APPEND script ")\n")
endforeach()
file(WRITE "${CTEST_FILE}" "${script}")
