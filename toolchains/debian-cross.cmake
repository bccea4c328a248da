# Shared part of the Debian cross toolchain files; included by
# aarch64-linux-gnu.cmake and arm-linux-gnueabihf.cmake after they set:
#   KG_CROSS_TRIPLE     GNU triple of Debian's cross compiler packages
#   KG_CROSS_PROCESSOR  CMAKE_SYSTEM_PROCESSOR value
#   KG_CROSS_ARCH_FLAGS architecture flags for C and C++
#   KG_CROSS_QEMU       qemu-user binary that runs the target's programs
#
# Compilers: /usr/bin/<triple>-gcc and -g++ (apt-get install g++-<triple>).
# Target headers and libraries: the cross packages' root /usr/<triple>, plus
# Debian multiarch paths (/usr/lib/<triple>, e.g. from libfoo-dev:arm64).
# Architecture-independent packages on the host (Eigen's CMake package in
# /usr/share/eigen3) stay visible; host programs are used as they are.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR ${KG_CROSS_PROCESSOR})
set(CMAKE_LIBRARY_ARCHITECTURE ${KG_CROSS_TRIPLE})

set(CMAKE_C_COMPILER /usr/bin/${KG_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER /usr/bin/${KG_CROSS_TRIPLE}-g++)
if(NOT EXISTS ${CMAKE_CXX_COMPILER})
  message(FATAL_ERROR "${CMAKE_CXX_COMPILER} not found: apt-get install g++-${KG_CROSS_TRIPLE}")
endif()

# *_FLAGS_INIT: the flags every configuration starts from, kept here and out
# of the project's CMakeLists.txt. -Wno-psabi silences GCC's notes that the
# ABI for passing some types changed in GCC 7.1 (armhf) and 10.1 (aarch64):
# everything in a build comes from the same GCC 12.
# KG_CROSS_TUNE (-D on the first cmake run) comes after the architecture
# flags, so it can refine them for one board: -mcpu=cortex-a72, or
# -mfpu=neon for a Cortex-A8/A9 (NEON without VFPv4).
set(CMAKE_C_FLAGS_INIT "${KG_CROSS_ARCH_FLAGS} ${KG_CROSS_TUNE} -Wno-psabi")
set(CMAKE_CXX_FLAGS_INIT "${KG_CROSS_ARCH_FLAGS} ${KG_CROSS_TUNE} -Wno-psabi")

# Search the target root first; "/" comes second so that multiarch target
# libraries (/usr/lib/<triple>, found through CMAKE_LIBRARY_ARCHITECTURE) and
# architecture-independent CMake packages (/usr/share/<name>/cmake) are found,
# while the host's own libraries in /usr/lib/<host triple> are not searched.
set(CMAKE_FIND_ROOT_PATH /usr/${KG_CROSS_TRIPLE} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config: the target's .pc files only, never the host's (a host
# libcamera.pc would link x86 libraries into an ARM build).
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${KG_CROSS_TRIPLE}/pkgconfig:/usr/${KG_CROSS_TRIPLE}/lib/pkgconfig:/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "")

# Cross-built programs (tests) run under qemu-user when it is installed:
# CMake uses this for ctest and gtest_discover_tests. -L points the emulator
# at the target's dynamic loader and libraries. The dynamic loader and libc
# must come from the same package: once the target's multiarch libc is
# installed (libc6:arm64, pulled in by libcamera-dev:arm64), the loader finds
# libc.so.6 in /usr/lib/<triple> through ld.so.cache, so the loader has to be
# that package's too (-L /); with the cross root's loader and the multiarch
# libc, programs hang. .ci/run picks the root the same way.
find_program(KG_CROSS_QEMU_PROGRAM ${KG_CROSS_QEMU} PATHS /usr/bin NO_CMAKE_FIND_ROOT_PATH)
if(KG_CROSS_QEMU_PROGRAM)
  if(EXISTS /usr/lib/${KG_CROSS_TRIPLE}/libc.so.6)
    set(KG_CROSS_QEMU_ROOT /)
  else()
    set(KG_CROSS_QEMU_ROOT /usr/${KG_CROSS_TRIPLE})
  endif()
  set(CMAKE_CROSSCOMPILING_EMULATOR ${KG_CROSS_QEMU_PROGRAM} -L ${KG_CROSS_QEMU_ROOT})
endif()
