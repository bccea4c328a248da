// Vector code (SIMD) and its portable reference. The loops that are most of
// a frame's time (blur, Hessian response, the search's leaf scan, the
// triangle check's sampling, the camera pixel-format conversions) have
// vector versions; each computes exactly what the portable loop computes
// (the tests compare them bit for bit), and simd_level() says which run.
//
// The level starts at the best this CPU and this build have, or at a lower
// one named by the environment variable KG_SIMD (scalar, baseline, sse2,
// neon, avx2). Lowering it rules vector code out when diagnosing a device
// or counting its cost: results do not change, only speed.
#pragma once

#include <cstdint>

namespace kg {

enum class SimdLevel : std::uint8_t {
  kScalar = 0,    // the portable C++ loops, the reference
  kBaseline = 1,  // vector code of the target's baseline ISA: SSE2 on x86-64, NEON on ARM
  kAvx2 = 2,      // x86-64 CPUs with AVX2, chosen at run time (the build stays SSE2)
};

// The level in use (process-wide).
SimdLevel simd_level();
// The best level this CPU and build support.
SimdLevel best_simd_level();
// Sets the level, clamped to best_simd_level(). Process-wide: not while
// another thread detects.
void set_simd_level(SimdLevel level);
// "scalar", "sse2" or "neon" (the baseline of this build), "avx2".
const char* simd_level_name(SimdLevel level);

}  // namespace kg
