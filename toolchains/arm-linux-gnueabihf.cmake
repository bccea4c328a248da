# 32-bit ARM (ARMv7-A, hard-float ABI, NEON) with Debian's cross compiler:
#   apt-get install g++-arm-linux-gnueabihf
#   cmake --preset cross-armhf && cmake --build --preset cross-armhf
# (or cmake -S . -B build/armhf -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-linux-gnueabihf.cmake ...)
# -mfpu=neon-vfpv4 enables NEON (__ARM_NEON, so NEON code paths are compiled)
# and VFPv4's fused multiply-add: Cortex-A5, A7, A12, A15, A17 and every ARMv8
# core running 32-bit code (Raspberry Pi 2 and later). Cortex-A8 and A9 have
# NEON without VFPv4: build for them with -DKG_CROSS_TUNE=-mfpu=neon on the
# first cmake run. Debian's armhf libraries (ARMv7-A, VFPv3-D16, hard-float)
# link with either.
set(KG_CROSS_TRIPLE arm-linux-gnueabihf)
set(KG_CROSS_PROCESSOR armv7l)
set(KG_CROSS_ARCH_FLAGS "-march=armv7-a -mfpu=neon-vfpv4 -mfloat-abi=hard")
set(KG_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
# 64-bit file offsets (off_t, stat) on this 32-bit target, as on the 64-bit
# ones: a file over 2 GiB can be stat()ed, so a 5 GiB input is refused for
# its size (TextFile.ReadWithinItsLimitOnly, tests/platform) instead of
# failing with EOVERFLOW. Programs built with this file (docs/example in
# .ci/run) get the same off_t as the libraries.
string(APPEND CMAKE_C_FLAGS_INIT " -D_FILE_OFFSET_BITS=64")
string(APPEND CMAKE_CXX_FLAGS_INIT " -D_FILE_OFFSET_BITS=64")
