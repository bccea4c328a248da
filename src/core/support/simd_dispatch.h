// Run-time choice of wider vector code on x86-64. The core is built for
// the baseline ISA (SSE2) so that one binary runs on every x86-64 CPU; the
// few loops that are most of a frame's keypoint time (blur and Hessian
// response) are compiled a second time for AVX2 and chosen when the CPU
// has it, as OpenCV's dispatcher does for its ORB baseline; the triangle
// patch check's lattice sampling has a hand-written AVX2 version (gathers). Without FMA
// in the target no multiply-add is fused, so both versions compute every
// pixel with the same operations in the same order: identical results
// (tested). ARM builds have one version (NEON is the baseline there).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(KG_NO_SIMD_DISPATCH)
#define KG_DISPATCH_AVX2 1
#define KG_TARGET_AVX2 [[gnu::target("avx2")]]
#endif

// Marks the body shared by both versions, so each is compiled for its
// caller's target.
#if defined(__GNUC__)
#define KG_ALWAYS_INLINE [[gnu::always_inline]] inline
#else
#define KG_ALWAYS_INLINE inline
#endif

namespace kg {

enum class SimdLevel { kBaseline, kAvx2 };

// The level the dispatched loops run at: kAvx2 when the build dispatches
// and the CPU has AVX2, unless lowered by set_simd_level().
SimdLevel simd_level();
// Sets the level (clamped to what the CPU has): tests compare the
// versions. Not for use while another thread detects.
void set_simd_level(SimdLevel level);
const char* simd_level_name(SimdLevel level);

}  // namespace kg
