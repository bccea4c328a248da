# 32-bit ARM (ARMv7-A, hard-float ABI, NEON) with Debian's cross compiler:
#   apt-get install g++-arm-linux-gnueabihf
#   cmake -S . -B build/armhf -DCMAKE_TOOLCHAIN_FILE=toolchains/arm-linux-gnueabihf.cmake \
#     -DKG_BUILD_TOOLS=OFF -DKG_BUILD_TESTS=OFF
# -mfpu=neon makes __ARM_NEON available, so NEON code paths are compiled.
set(KG_CROSS_TRIPLE arm-linux-gnueabihf)
set(KG_CROSS_PROCESSOR armv7l)
# -Wno-psabi: silences GCC's notes that the passing of some std:: iterator
# types changed in GCC 7.1; everything here is built by one GCC 12.
set(KG_CROSS_ARCH_FLAGS "-march=armv7-a -mfpu=neon -mfloat-abi=hard -Wno-psabi")
set(KG_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
