# Cross compilation for arm64 (a 64-bit Raspberry Pi OS / Debian 12 Pi):
# Debian's cross compiler (g++-aarch64-linux-gnu) against an arm64 sysroot
# of Debian packages, the programs run by qemu-user where the build runs
# them (test discovery, ctest). scripts/cross_pi.sh makes the sysroot and
# passes -DINSPECT_SYSROOT=DIR (or the environment's INSPECT_SYSROOT).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

if(NOT INSPECT_SYSROOT AND DEFINED ENV{INSPECT_SYSROOT})
  set(INSPECT_SYSROOT "$ENV{INSPECT_SYSROOT}")
endif()
if(NOT INSPECT_SYSROOT OR NOT EXISTS "${INSPECT_SYSROOT}/usr/include")
  message(FATAL_ERROR "toolchain-aarch64: INSPECT_SYSROOT='${INSPECT_SYSROOT}' is not an arm64 sysroot "
                      "(scripts/cross_pi.sh makes one)")
endif()
# try_compile projects read the toolchain file again: pass the sysroot on.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES INSPECT_SYSROOT)

set(CMAKE_SYSROOT "${INSPECT_SYSROOT}")
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Libraries, headers and CMake packages from the sysroot only; programs
# (protoc, pkg-config) from the host.
set(CMAKE_FIND_ROOT_PATH "${INSPECT_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${INSPECT_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR} "${INSPECT_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${INSPECT_SYSROOT}/usr/share/pkgconfig")
set(Protobuf_PROTOC_EXECUTABLE /usr/bin/protoc CACHE FILEPATH "the host's protoc (same Debian version as the sysroot's libprotobuf)")

# arm64 programs run under qemu-user with the sysroot's loader and libraries.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L "${INSPECT_SYSROOT}")
