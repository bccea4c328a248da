#include "core/support/simd_dispatch.h"

#include <cstdlib>
#include <cstring>

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

// The starting level: the CPU's, or lower when the environment variable
// KG_SIMD names a lower one (scalar, baseline, sse2, neon, avx2), so that any
// program, with no option of its own, can run the portable loops.
SimdLevel start_level() {
  const SimdLevel best = cpu_level();
  const char* asked = std::getenv("KG_SIMD");
  if (asked == nullptr) return best;
  SimdLevel level = best;
  if (std::strcmp(asked, "scalar") == 0) {
    level = SimdLevel::kScalar;
  } else if (std::strcmp(asked, "baseline") == 0 || std::strcmp(asked, "sse2") == 0 ||
             std::strcmp(asked, "neon") == 0) {
    level = SimdLevel::kBaseline;
  }
  return static_cast<int>(level) < static_cast<int>(best) ? level : best;
}

SimdLevel& current() {
  static SimdLevel level = start_level();
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
