#include "core/selection/triangle_patch.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/support/simd_dispatch.h"

#if defined(KG_DISPATCH_AVX2)
#include <immintrin.h>
#elif defined(KG_NEON_FLOAT)
#include <arm_neon.h>
#endif

namespace kg {

namespace {

constexpr int kLatticeSteps = 9;  // (9 + 1) (9 + 2) / 2 = 55 points
static_assert((kLatticeSteps + 1) * (kLatticeSteps + 2) / 2 == kTriangleSamples);
// The triangle is enlarged about its centroid by this factor: the arcs'
// profiles already matched, so the triangle's own edges agree by
// construction; the texture around it is what tells. On box_in_scene,
// correspondences over 100 px off correlate 0.63 on average enlarged 1.6x,
// 0.40 enlarged 3x, while the right ones stay above 0.7 (docs/RESULTS.md).
constexpr float kEnlarge = 3.0f;
// Smallest triangle area, in the pixels of the coarser image, worth
// judging: below it the samples repeat a handful of pixels.
constexpr float kMinArea = 6.f;
constexpr int kMaxSubsamples = 3;       // per axis, in the finer image
constexpr int kMinInside = 40;          // samples inside both images
constexpr float kMinVariance = 4.f;     // grey levels squared per sample: flat below
constexpr float kMaxScaleRatio = 16.f;  // of the two images' pixels per triangle edge

float signed_area(const Point2f& a, const Point2f& b, const Point2f& c) {
  return 0.5f * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
}

// The lattice's barycentric coordinates (l0, l1, l2) about the centroid,
// padded to whole vectors of 8 (the padding lanes are never kept).
constexpr int kLatticePadded = 56;
struct Lattice {
  float l0[kLatticePadded] = {}, l1[kLatticePadded] = {}, l2[kLatticePadded] = {};
};
constexpr Lattice make_lattice() {
  Lattice t;
  const float inv_steps = 1.f / static_cast<float>(kLatticeSteps);
  int k = 0;
  for (int i = 0; i <= kLatticeSteps; ++i) {
    for (int j = 0; i + j <= kLatticeSteps; ++j, ++k) {
      t.l0[k] = static_cast<float>(i) * inv_steps - 1.f / 3.f;
      t.l1[k] = static_cast<float>(j) * inv_steps - 1.f / 3.f;
      t.l2[k] = -t.l0[k] - t.l1[k];
    }
  }
  return t;
}
constexpr Lattice kLattice = make_lattice();

// One image as the lattice samples it: each point is the mean of sub x sub
// bilinear samples spaced `step` apart (sub 1: one sample).
struct SampledImage {
  const std::uint8_t* pixels;
  int width, height;
  std::ptrdiff_t stride;
  int sub;
  float step;
};

// Lattice point k of the triangle t (enlarged about its centroid c).
Point2f lattice_point(const Point2f& c, const Point2f* t, int k) {
  const float l0 = kLattice.l0[k], l1 = kLattice.l1[k], l2 = kLattice.l2[k];
  return {c.x + kEnlarge * (l0 * t[0].x + l1 * t[1].x + l2 * t[2].x),
          c.y + kEnlarge * (l0 * t[0].y + l1 * t[1].y + l2 * t[2].y)};
}

Point2f centroid(const Point2f* t) {
  return {(t[0].x + t[1].x + t[2].x) / 3.f, (t[0].y + t[1].y + t[2].y) / 3.f};
}

// Bilinear sample; false outside [0, width - 1) x [0, height - 1).
bool sample(const SampledImage& im, float x, float y, float& value) {
  if (!(x >= 0.f && y >= 0.f && x < static_cast<float>(im.width - 1) &&
        y < static_cast<float>(im.height - 1)))
    return false;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const std::uint8_t* r0 = im.pixels + static_cast<std::ptrdiff_t>(y0) * im.stride + x0;
  const std::uint8_t* r1 = r0 + im.stride;
  const float top = r0[0] + fx * static_cast<float>(r0[1] - r0[0]);
  const float bottom = r1[0] + fx * static_cast<float>(r1[1] - r1[0]);
  value = top + fy * (bottom - top);
  return true;
}

// The mean of the sub x sub samples around (x, y).
bool averaged(const SampledImage& im, float x, float y, float& value) {
  if (im.sub == 1) return sample(im, x, y, value);
  const float first = -0.5f * im.step * static_cast<float>(im.sub - 1);
  float sum = 0.f;
  for (int j = 0; j < im.sub; ++j) {
    for (int i = 0; i < im.sub; ++i) {
      float v;
      if (!sample(im, x + first + im.step * static_cast<float>(i),
                  y + first + im.step * static_cast<float>(j), v))
        return false;
      sum += v;
    }
  }
  value = sum / static_cast<float>(im.sub * im.sub);
  return true;
}

// Samples the lattice in both images: for each point inside both, in
// lattice order, its (l0, l1) in lu, lv and the two values in ta, tf.
// Returns their count.
int sample_lattice_baseline(const SampledImage& look, const Point2f* a, const SampledImage& seen,
                            const Point2f* scene, float* ta, float* tf, float* lu, float* lv) {
  const Point2f ca = centroid(a), cf = centroid(scene);
  int n = 0;
  for (int k = 0; k < kTriangleSamples; ++k) {
    const Point2f pa = lattice_point(ca, a, k), pf = lattice_point(cf, scene, k);
    float va, vf;
    if (!averaged(look, pa.x, pa.y, va) || !averaged(seen, pf.x, pf.y, vf)) continue;
    lu[n] = kLattice.l0[k];
    lv[n] = kLattice.l1[k];
    ta[n] = va;
    tf[n] = vf;
    ++n;
  }
  return n;
}

#if defined(KG_DISPATCH_AVX2)
// The same on 8 lattice points at a time, with gathers: the same float
// operations in the same order per point (no FMA in the target), so the
// same values bit for bit (tested). A gather reads 4 bytes for the 2 a
// row needs: from x0 - 2 (the upper two bytes) when x0 >= 2, else from x0,
// which stays inside the row for images at least 5 pixels wide.
bool gatherable(const SampledImage& im) {
  return im.width >= 5 && im.height >= 2 && im.stride >= im.width &&
         static_cast<double>(im.height) * static_cast<double>(im.stride) < 2147483647.0;
}

// Vectors travel by reference: the file is compiled for the baseline, and
// passing them by value would change the calling convention.
struct Samples8 {
  __m256 value;
  __m256 inside;  // all ones where every sample was inside
};

KG_TARGET_AVX2 inline __m256i pixel8(const __m256i& row, const __m256i& shift) {
  return _mm256_and_si256(_mm256_srlv_epi32(row, shift), _mm256_set1_epi32(0xff));
}

KG_TARGET_AVX2 inline __m256 lerp8(const __m256& from, const __m256& to_minus_from,
                                   const __m256& t) {
  return _mm256_add_ps(from, _mm256_mul_ps(t, to_minus_from));
}

KG_TARGET_AVX2 void sample8(const SampledImage& im, const __m256& x_in, const __m256& y_in,
                            Samples8& out) {
  const __m256 zero = _mm256_setzero_ps();
  const __m256 inside = _mm256_and_ps(
      _mm256_and_ps(_mm256_cmp_ps(x_in, zero, _CMP_GE_OQ), _mm256_cmp_ps(y_in, zero, _CMP_GE_OQ)),
      _mm256_and_ps(
          _mm256_cmp_ps(x_in, _mm256_set1_ps(static_cast<float>(im.width - 1)), _CMP_LT_OQ),
          _mm256_cmp_ps(y_in, _mm256_set1_ps(static_cast<float>(im.height - 1)), _CMP_LT_OQ)));
  // Points outside read pixel (0, 0) instead; they are dropped.
  const __m256 x = _mm256_and_ps(x_in, inside), y = _mm256_and_ps(y_in, inside);
  const __m256i x0 = _mm256_cvttps_epi32(x), y0 = _mm256_cvttps_epi32(y);
  const __m256 fx = _mm256_sub_ps(x, _mm256_cvtepi32_ps(x0));
  const __m256 fy = _mm256_sub_ps(y, _mm256_cvtepi32_ps(y0));
  const __m256i back =
      _mm256_and_si256(_mm256_cmpgt_epi32(x0, _mm256_set1_epi32(1)), _mm256_set1_epi32(2));
  const __m256i stride = _mm256_set1_epi32(static_cast<int>(im.stride));
  const __m256i at = _mm256_sub_epi32(_mm256_add_epi32(_mm256_mullo_epi32(y0, stride), x0), back);
  const auto* base = reinterpret_cast<const int*>(im.pixels);
  const __m256i row0 = _mm256_i32gather_epi32(base, at, 1);
  const __m256i row1 = _mm256_i32gather_epi32(base, _mm256_add_epi32(at, stride), 1);
  const __m256i shift = _mm256_slli_epi32(back, 3);  // 16 bits when read from x0 - 2
  const __m256i next = _mm256_add_epi32(shift, _mm256_set1_epi32(8));
  const __m256i p00 = pixel8(row0, shift), p01 = pixel8(row0, next);
  const __m256i p10 = pixel8(row1, shift), p11 = pixel8(row1, next);
  // top = r0[0] + fx (r0[1] - r0[0]), as sample() computes it.
  const __m256 top =
      lerp8(_mm256_cvtepi32_ps(p00), _mm256_cvtepi32_ps(_mm256_sub_epi32(p01, p00)), fx);
  const __m256 bottom =
      lerp8(_mm256_cvtepi32_ps(p10), _mm256_cvtepi32_ps(_mm256_sub_epi32(p11, p10)), fx);
  out.value = lerp8(top, _mm256_sub_ps(bottom, top), fy);
  out.inside = inside;
}

KG_TARGET_AVX2 void averaged8(const SampledImage& im, const __m256& x, const __m256& y,
                              Samples8& out) {
  if (im.sub == 1) return sample8(im, x, y, out);
  const float first = -0.5f * im.step * static_cast<float>(im.sub - 1);
  const __m256 x_first = _mm256_add_ps(x, _mm256_set1_ps(first));
  const __m256 y_first = _mm256_add_ps(y, _mm256_set1_ps(first));
  out.value = _mm256_setzero_ps();
  out.inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  Samples8 s;
  for (int j = 0; j < im.sub; ++j) {
    const __m256 yj = _mm256_add_ps(y_first, _mm256_set1_ps(im.step * static_cast<float>(j)));
    for (int i = 0; i < im.sub; ++i) {
      const __m256 xi = _mm256_add_ps(x_first, _mm256_set1_ps(im.step * static_cast<float>(i)));
      sample8(im, xi, yj, s);
      out.value = _mm256_add_ps(out.value, s.value);
      out.inside = _mm256_and_ps(out.inside, s.inside);
    }
  }
  out.value = _mm256_div_ps(out.value, _mm256_set1_ps(static_cast<float>(im.sub * im.sub)));
}

// c0 + kEnlarge (l0 t0 + l1 t1 + l2 t2) for lattice points k..k+7.
KG_TARGET_AVX2 void along8(int k, float c0, float t0, float t1, float t2, __m256& out) {
  const __m256 sum = _mm256_add_ps(
      _mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(kLattice.l0 + k), _mm256_set1_ps(t0)),
                    _mm256_mul_ps(_mm256_loadu_ps(kLattice.l1 + k), _mm256_set1_ps(t1))),
      _mm256_mul_ps(_mm256_loadu_ps(kLattice.l2 + k), _mm256_set1_ps(t2)));
  out = _mm256_add_ps(_mm256_set1_ps(c0), _mm256_mul_ps(_mm256_set1_ps(kEnlarge), sum));
}

KG_TARGET_AVX2 int sample_lattice_avx2(const SampledImage& look, const Point2f* a,
                                       const SampledImage& seen, const Point2f* scene, float* ta,
                                       float* tf, float* lu, float* lv) {
  const Point2f ca = centroid(a), cf = centroid(scene);
  int n = 0;
  for (int k = 0; k < kTriangleSamples; k += 8) {
    __m256 xa, ya, xf, yf;
    along8(k, ca.x, a[0].x, a[1].x, a[2].x, xa);
    along8(k, ca.y, a[0].y, a[1].y, a[2].y, ya);
    along8(k, cf.x, scene[0].x, scene[1].x, scene[2].x, xf);
    along8(k, cf.y, scene[0].y, scene[1].y, scene[2].y, yf);
    Samples8 va, vf;
    averaged8(look, xa, ya, va);
    averaged8(seen, xf, yf, vf);
    int kept = _mm256_movemask_ps(_mm256_and_ps(va.inside, vf.inside));
    if (k + 8 > kTriangleSamples) kept &= (1 << (kTriangleSamples - k)) - 1;
    alignas(32) float values_a[8], values_f[8];
    _mm256_store_ps(values_a, va.value);
    _mm256_store_ps(values_f, vf.value);
    for (int lane = 0; lane < 8; ++lane) {
      if ((kept >> lane & 1) == 0) continue;
      lu[n] = kLattice.l0[k + lane];
      lv[n] = kLattice.l1[k + lane];
      ta[n] = values_a[lane];
      tf[n] = values_f[lane];
      ++n;
    }
  }
  return n;
}
#endif

#if defined(KG_NEON_FLOAT)
// The same on 4 lattice points at a time with NEON (AArch64), which has no
// gathers: coordinates, weights and blends in vectors, each point's four
// pixels read lane by lane; per point the same float operations in the
// same order as sample() and averaged(), so the same values bit for bit
// (tested). Points outside read pixel (0, 0) and its neighbours instead
// (then dropped), so the image needs 2 x 2 pixels.
bool neon_samplable(const SampledImage& im) {
  return im.width >= 2 && im.height >= 2 && im.stride >= im.width;
}

struct Samples4 {
  float32x4_t value;
  uint32x4_t inside;  // all ones where every sample was inside
};

void sample4(const SampledImage& im, const float32x4_t& x_in, const float32x4_t& y_in,
             Samples4& out) {
  const float32x4_t zero = vdupq_n_f32(0.f);
  const uint32x4_t inside =
      vandq_u32(vandq_u32(vcgeq_f32(x_in, zero), vcgeq_f32(y_in, zero)),
                vandq_u32(vcltq_f32(x_in, vdupq_n_f32(static_cast<float>(im.width - 1))),
                          vcltq_f32(y_in, vdupq_n_f32(static_cast<float>(im.height - 1)))));
  const float32x4_t x = vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(x_in), inside));
  const float32x4_t y = vreinterpretq_f32_u32(vandq_u32(vreinterpretq_u32_f32(y_in), inside));
  const int32x4_t x0 = vcvtq_s32_f32(x), y0 = vcvtq_s32_f32(y);
  const float32x4_t fx = vsubq_f32(x, vcvtq_f32_s32(x0));
  const float32x4_t fy = vsubq_f32(y, vcvtq_f32_s32(y0));
  alignas(16) std::int32_t xs[4], ys[4], p00[4], p01[4], p10[4], p11[4];
  vst1q_s32(xs, x0);
  vst1q_s32(ys, y0);
  for (int lane = 0; lane < 4; ++lane) {
    const std::uint8_t* r0 =
        im.pixels + static_cast<std::ptrdiff_t>(ys[lane]) * im.stride + xs[lane];
    const std::uint8_t* r1 = r0 + im.stride;
    p00[lane] = r0[0];
    p01[lane] = r0[1];
    p10[lane] = r1[0];
    p11[lane] = r1[1];
  }
  const int32x4_t q00 = vld1q_s32(p00), q01 = vld1q_s32(p01);
  const int32x4_t q10 = vld1q_s32(p10), q11 = vld1q_s32(p11);
  // top = r0[0] + fx (r0[1] - r0[0]), as sample() computes it.
  const float32x4_t top =
      vaddq_f32(vcvtq_f32_s32(q00), vmulq_f32(fx, vcvtq_f32_s32(vsubq_s32(q01, q00))));
  const float32x4_t bottom =
      vaddq_f32(vcvtq_f32_s32(q10), vmulq_f32(fx, vcvtq_f32_s32(vsubq_s32(q11, q10))));
  out.value = vaddq_f32(top, vmulq_f32(fy, vsubq_f32(bottom, top)));
  out.inside = inside;
}

void averaged4(const SampledImage& im, const float32x4_t& x, const float32x4_t& y, Samples4& out) {
  if (im.sub == 1) return sample4(im, x, y, out);
  const float first = -0.5f * im.step * static_cast<float>(im.sub - 1);
  const float32x4_t x_first = vaddq_f32(x, vdupq_n_f32(first));
  const float32x4_t y_first = vaddq_f32(y, vdupq_n_f32(first));
  out.value = vdupq_n_f32(0.f);
  out.inside = vdupq_n_u32(0xffffffffu);
  Samples4 s;
  for (int j = 0; j < im.sub; ++j) {
    const float32x4_t yj = vaddq_f32(y_first, vdupq_n_f32(im.step * static_cast<float>(j)));
    for (int i = 0; i < im.sub; ++i) {
      const float32x4_t xi = vaddq_f32(x_first, vdupq_n_f32(im.step * static_cast<float>(i)));
      sample4(im, xi, yj, s);
      out.value = vaddq_f32(out.value, s.value);
      out.inside = vandq_u32(out.inside, s.inside);
    }
  }
  out.value = vdivq_f32(out.value, vdupq_n_f32(static_cast<float>(im.sub * im.sub)));
}

// c0 + kEnlarge (l0 t0 + l1 t1 + l2 t2) for lattice points k..k+3.
float32x4_t along4(int k, float c0, float t0, float t1, float t2) {
  const float32x4_t sum = vaddq_f32(vaddq_f32(vmulq_n_f32(vld1q_f32(kLattice.l0 + k), t0),
                                              vmulq_n_f32(vld1q_f32(kLattice.l1 + k), t1)),
                                    vmulq_n_f32(vld1q_f32(kLattice.l2 + k), t2));
  return vaddq_f32(vdupq_n_f32(c0), vmulq_n_f32(sum, kEnlarge));
}

int sample_lattice_neon(const SampledImage& look, const Point2f* a, const SampledImage& seen,
                        const Point2f* scene, float* ta, float* tf, float* lu, float* lv) {
  const Point2f ca = centroid(a), cf = centroid(scene);
  int n = 0;
  for (int k = 0; k < kTriangleSamples; k += 4) {
    Samples4 va, vf;
    averaged4(look, along4(k, ca.x, a[0].x, a[1].x, a[2].x),
              along4(k, ca.y, a[0].y, a[1].y, a[2].y), va);
    averaged4(seen, along4(k, cf.x, scene[0].x, scene[1].x, scene[2].x),
              along4(k, cf.y, scene[0].y, scene[1].y, scene[2].y), vf);
    alignas(16) std::uint32_t kept[4];
    alignas(16) float values_a[4], values_f[4];
    vst1q_u32(kept, vandq_u32(va.inside, vf.inside));
    vst1q_f32(values_a, va.value);
    vst1q_f32(values_f, vf.value);
    for (int lane = 0; lane < 4 && k + lane < kTriangleSamples; ++lane) {
      if (kept[lane] == 0) continue;
      lu[n] = kLattice.l0[k + lane];
      lv[n] = kLattice.l1[k + lane];
      ta[n] = values_a[lane];
      tf[n] = values_f[lane];
      ++n;
    }
  }
  return n;
}
#endif

// Solves the symmetric 3x3 system m x = r by Cramer's rule.
bool solve3(const double m[3][3], const double r[3], double x[3]) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
  if (!(std::fabs(det) > 1e-12)) return false;
  const double d = 1.0 / det;
  for (int k = 0; k < 3; ++k) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] = j == k ? r[i] : m[i][j];
    x[k] = d * (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]));
  }
  return true;
}

}  // namespace

TrianglePatch triangle_patch_correlation(const ModelAppearance& appearance, ImageView frame,
                                         const Point2f* model, const Point2f* scene) {
  TrianglePatch out;
  if (appearance.empty() || frame.empty() || !(appearance.scale > 0.f)) return out;
  // The centre of appearance pixel u is model pixel (u + 0.5) / s - 0.5
  // (area resampling; ModelAppearance).
  const float s = appearance.scale;
  Point2f a[3];
  for (int i = 0; i < 3; ++i)
    a[i] = {(model[i].x + 0.5f) * s - 0.5f, (model[i].y + 0.5f) * s - 0.5f};
  const float area_a = std::fabs(signed_area(a[0], a[1], a[2]));
  const float area_f = std::fabs(signed_area(scene[0], scene[1], scene[2]));
  if (!(area_a > 0.f) || !(area_f > 0.f) || !std::isfinite(area_a) || !std::isfinite(area_f))
    return out;
  // Frame pixels per appearance pixel along an edge (the triangle's mean).
  const float ratio = std::sqrt(area_f / area_a);
  if (ratio > kMaxScaleRatio || ratio < 1.f / kMaxScaleRatio) return out;
  if (std::min(area_a, area_f) < kMinArea) return out;
  // The finer image is averaged over the coarser one's pixel.
  int sub_a = 1, sub_f = 1;
  float step_a = 1.f, step_f = 1.f;
  if (ratio > 1.f) {
    sub_f = std::min(kMaxSubsamples, static_cast<int>(std::lround(ratio)));
    step_f = ratio / static_cast<float>(sub_f);
  } else {
    const float inverse = 1.f / ratio;
    sub_a = std::min(kMaxSubsamples, static_cast<int>(std::lround(inverse)));
    step_a = inverse / static_cast<float>(sub_a);
  }
  const SampledImage look{
      appearance.pixels, appearance.width, appearance.height, appearance.width, sub_a, step_a};
  const SampledImage seen{frame.data, frame.width, frame.height, frame.stride, sub_f, step_f};
  float ta[kLatticePadded], tf[kLatticePadded], lu[kLatticePadded], lv[kLatticePadded];
  int n = 0;
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2 && gatherable(look) && gatherable(seen))
    n = sample_lattice_avx2(look, a, seen, scene, ta, tf, lu, lv);
  else
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar && neon_samplable(look) && neon_samplable(seen))
    n = sample_lattice_neon(look, a, seen, scene, ta, tf, lu, lv);
  else
#endif
    n = sample_lattice_baseline(look, a, seen, scene, ta, tf, lu, lv);
  if (n < kMinInside) return out;
  // Project out the best plane a + b l0 + c l1 from both: the arcs'
  // profiles already matched, so a shared intensity ramp across the
  // triangle is no evidence; what is left is the texture the arcs missed.
  double m[3][3] = {}, ra[3] = {}, rf[3] = {};
  for (int i = 0; i < n; ++i) {
    const double basis[3] = {1.0, lu[i], lv[i]};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] += basis[r] * basis[c];
      ra[r] += basis[r] * ta[i];
      rf[r] += basis[r] * tf[i];
    }
  }
  double pa[3], pf[3];
  if (!solve3(m, ra, pa) || !solve3(m, rf, pf)) return out;
  float saa = 0.f, sff = 0.f, saf = 0.f;
  for (int i = 0; i < n; ++i) {
    const auto da = static_cast<float>(ta[i] - (pa[0] + pa[1] * lu[i] + pa[2] * lv[i]));
    const auto df = static_cast<float>(tf[i] - (pf[0] + pf[1] * lu[i] + pf[2] * lv[i]));
    saa += da * da;
    sff += df * df;
    saf += da * df;
  }
  const float floor = kMinVariance * static_cast<float>(n);
  if (saa < floor || sff < floor) return out;
  out.measured = true;
  out.correlation = std::clamp(saf / std::sqrt(saa * sff), -1.f, 1.f);
  return out;
}

}  // namespace kg
