# The firmware core's sources, for both of its builds: the host's
# (firmware/CMakeLists.txt, unit tests) and the MCU's (firmware/mcu). Paths
# relative to the source tree's root.
set(INSPECT_FIRMWARE_CORE_SOURCES
  firmware/core/analog_inputs.cpp
  firmware/core/firmware_core.cpp
  firmware/core/odometry.cpp
  firmware/core/ptz_servo.cpp
  firmware/core/ultrasonic.cpp
  firmware/core/wheel_speed.cpp)
