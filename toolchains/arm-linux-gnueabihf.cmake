# 32-bit ARM (ARMv7-A, hard-float ABI, NEON) with Debian's cross compiler:
#   apt-get install g++-arm-linux-gnueabihf
#   cmake -S . -B build/armhf -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-linux-gnueabihf.cmake \
#     -DKG_BUILD_TOOLS=OFF -DKG_BUILD_TESTS=OFF
# -mfpu=neon makes __ARM_NEON available, so NEON code paths are compiled.
set(KG_CROSS_TRIPLE arm-linux-gnueabihf)
set(KG_CROSS_PROCESSOR armv7l)
set(KG_CROSS_ARCH_FLAGS "-march=armv7-a -mfpu=neon -mfloat-abi=hard")
set(KG_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
