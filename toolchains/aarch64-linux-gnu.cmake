# 64-bit ARM (ARMv8-A, AArch64; NEON is part of the base architecture) with
# Debian's cross compiler:
#   apt-get install g++-aarch64-linux-gnu
#   cmake --preset cross-aarch64 && cmake --build --preset cross-aarch64
# (or cmake -S . -B build/aarch64 -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-linux-gnu.cmake ...)
# Tune for a board with -DKG_CROSS_TUNE=-mcpu=cortex-a72 (Raspberry Pi 4) or
# -mcpu=cortex-a76 (Pi 5) on the first cmake run.
set(KG_CROSS_TRIPLE aarch64-linux-gnu)
set(KG_CROSS_PROCESSOR aarch64)
set(KG_CROSS_ARCH_FLAGS "-march=armv8-a")
set(KG_CROSS_QEMU qemu-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
