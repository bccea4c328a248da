// How the core compiles its vector code (keygraph/simd.h is the contract).
// The core is built for the baseline ISA (SSE2 on x86-64, NEON on ARM) so
// that one binary runs on every CPU of its architecture. Loops written
// with baseline intrinsics (the leaf scan) are compiled in when the target
// has them; loops worth AVX2 (blur, Hessian response: the same source
// compiled a second time; the triangle check's sampling: hand-written
// gathers) get an x86-64 AVX2 twin. Every such loop branches on
// simd_level() at its entry, so one switch chooses them all. Without FMA in
// the target no multiply-add is fused, so every version computes every
// value with the same operations in the same order: identical results.
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

// Marks the body shared by both versions, so each is compiled for its
// caller's target.
#if defined(__GNUC__)
#define KG_ALWAYS_INLINE [[gnu::always_inline]] inline
#else
#define KG_ALWAYS_INLINE inline
#endif
