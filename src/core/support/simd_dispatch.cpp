#include "core/support/simd_dispatch.h"

namespace kg {
namespace {

SimdLevel cpu_level() {
#if defined(KG_DISPATCH_AVX2)
  return __builtin_cpu_supports("avx2") ? SimdLevel::kAvx2 : SimdLevel::kBaseline;
#else
  return SimdLevel::kBaseline;
#endif
}

SimdLevel& current() {
  static SimdLevel level = cpu_level();
  return level;
}

}  // namespace

SimdLevel simd_level() {
  return current();
}

void set_simd_level(SimdLevel level) {
  current() = level == SimdLevel::kAvx2 ? cpu_level() : SimdLevel::kBaseline;
}

const char* simd_level_name(SimdLevel level) {
  return level == SimdLevel::kAvx2 ? "avx2" : "baseline";
}

}  // namespace kg
