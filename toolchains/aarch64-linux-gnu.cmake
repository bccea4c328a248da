# 64-bit ARM (ARMv8-A, AArch64; NEON is part of the base architecture) with
# Debian's cross compiler:
#   apt-get install g++-aarch64-linux-gnu
#   cmake -S . -B build/aarch64 -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake \
#     -DKG_BUILD_TOOLS=OFF -DKG_BUILD_TESTS=OFF
# Tune for a board by adding e.g. -mcpu=cortex-a72 to CMAKE_CXX_FLAGS.
set(KG_CROSS_TRIPLE aarch64-linux-gnu)
set(KG_CROSS_PROCESSOR aarch64)
set(KG_CROSS_ARCH_FLAGS "-march=armv8-a")
set(KG_CROSS_QEMU qemu-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
