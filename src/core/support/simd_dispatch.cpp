#include "core/support/simd_dispatch.h"

namespace kg {
namespace {

SimdLevel cpu_level() {
#if defined(KG_DISPATCH_AVX2)
  if (__builtin_cpu_supports("avx2")) return SimdLevel::kAvx2;
#endif
#if defined(KG_SIMD_NEON) || defined(KG_SIMD_SSE2)
  return SimdLevel::kBaseline;
#else
  return SimdLevel::kScalar;
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

SimdLevel best_simd_level() {
  return cpu_level();
}

void set_simd_level(SimdLevel level) {
  const SimdLevel best = cpu_level();
  current() = static_cast<int>(level) < static_cast<int>(best) ? level : best;
}

const char* simd_level_name(SimdLevel level) {
  switch (level) {
    case SimdLevel::kScalar:
      return "scalar";
    case SimdLevel::kBaseline:
#if defined(KG_SIMD_NEON)
      return "neon";
#else
      return "sse2";
#endif
    case SimdLevel::kAvx2:
      return "avx2";
  }
  return "scalar";
}

}  // namespace kg
