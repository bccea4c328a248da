// How the core compiles its vector code (keygraph/simd.h is the contract).
// The core is built for the baseline ISA (SSE2 on x86-64, NEON on ARM) so
// that one binary runs on every CPU of its architecture. Loops written
// with baseline intrinsics (the leaf scan; on AArch64 the blur, the Hessian
// response and the appearance alignment's sampling and normal equations)
// are compiled in when the target has them and run unless
// the level is kScalar; loops worth AVX2 get an x86-64 AVX2 twin (the
// Hessian response, the float conversion and halving: the same source
// compiled a second time; the blur's passes: GCC vector types, shared with
// the NEON passes; the Hessian candidate test and the triangle check's
// sampling: hand-written intrinsics). Every such loop branches on
// simd_level() at its entry, so one switch chooses them all. The core is
// compiled with -ffp-contract=off (AArch64 has FMA, x86-64's baseline not):
// no multiply-add is fused, so every version computes every value with the
// same operations in the same order: identical results.
#pragma once

#include "keygraph/simd.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(KG_NO_SIMD_DISPATCH)
#define KG_DISPATCH_AVX2 1
#define KG_TARGET_AVX2 [[gnu::target("avx2")]]
#endif

#if defined(__ARM_NEON) || defined(__ARM_NEON__)
#define KG_SIMD_NEON 1
#elif defined(__SSE2__)
#define KG_SIMD_SSE2 1
#endif

// Float loops written with NEON intrinsics (blur, Hessian response) exist
// on AArch64 only: there NEON's float arithmetic is IEEE, as the scalar
// code's; ARMv7's NEON flushes denormals to zero, so armhf keeps the
// portable loops. Integer NEON code (the leaf scan) runs on both.
#if defined(KG_SIMD_NEON) && defined(__aarch64__)
#define KG_NEON_FLOAT 1
#endif

// Marks the body shared by both versions, so each is compiled for its
// caller's target.
#if defined(__GNUC__)
#define KG_ALWAYS_INLINE [[gnu::always_inline]] inline
#else
#define KG_ALWAYS_INLINE inline
#endif
