#include "core/image/blur.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "core/support/simd_dispatch.h"

namespace kg {
namespace {

// Kernels are truncated at this radius (sigma above ~170 px, far beyond any
// use here); the bound keeps the kernel on the stack so blurring never
// allocates.
constexpr int kMaxRadius = 512;

// Half of a symmetric kernel: w[0] is the centre tap, w[i] the taps at +-i.
struct Kernel {
  std::array<float, kMaxRadius + 1> w;
  int radius = 0;
};

void make_kernel(float sigma, Kernel& k) {
  k.radius = blur_radius(sigma);
  const double inv_two_var = 1.0 / (2.0 * static_cast<double>(sigma) * sigma);
  double sum = 1.0;
  for (int i = 1; i <= k.radius; ++i) sum += 2.0 * std::exp(-i * i * inv_two_var);
  k.w[0] = static_cast<float>(1.0 / sum);
  for (int i = 1; i <= k.radius; ++i)
    k.w[i] = static_cast<float>(std::exp(-i * i * inv_two_var) / sum);
}

// Vertical pass for output row y: rows come from `row(i)` (clamped, so the
// border rows are replicated). Taps outer, pixels inner, so the inner loop is
// a contiguous multiply-add the compiler vectorises.
template <class T, class RowFn>
KG_ALWAYS_INLINE void vertical_row(RowFn row, int y, int w, int h, const Kernel& k, float* out) {
  const T* c = row(y);
  const float k0 = k.w[0];
  for (int x = 0; x < w; ++x) out[x] = k0 * static_cast<float>(c[x]);
  int i = 1;
  for (; i + 3 <= k.radius; i += 4) {
    const T* a0 = row(std::max(y - i, 0));
    const T* b0 = row(std::min(y + i, h - 1));
    const T* a1 = row(std::max(y - i - 1, 0));
    const T* b1 = row(std::min(y + i + 1, h - 1));
    const T* a2 = row(std::max(y - i - 2, 0));
    const T* b2 = row(std::min(y + i + 2, h - 1));
    const T* a3 = row(std::max(y - i - 3, 0));
    const T* b3 = row(std::min(y + i + 3, h - 1));
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    const float kc = k.w[i + 2];
    const float kd = k.w[i + 3];
    for (int x = 0; x < w; ++x)
      out[x] += (ka * (static_cast<float>(a0[x]) + static_cast<float>(b0[x])) +
                 kb * (static_cast<float>(a1[x]) + static_cast<float>(b1[x]))) +
                (kc * (static_cast<float>(a2[x]) + static_cast<float>(b2[x])) +
                 kd * (static_cast<float>(a3[x]) + static_cast<float>(b3[x])));
  }
  for (; i + 1 <= k.radius; i += 2) {
    const T* a0 = row(std::max(y - i, 0));
    const T* b0 = row(std::min(y + i, h - 1));
    const T* a1 = row(std::max(y - i - 1, 0));
    const T* b1 = row(std::min(y + i + 1, h - 1));
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    for (int x = 0; x < w; ++x)
      out[x] += ka * (static_cast<float>(a0[x]) + static_cast<float>(b0[x])) +
                kb * (static_cast<float>(a1[x]) + static_cast<float>(b1[x]));
  }
  if (i <= k.radius) {
    const T* a = row(std::max(y - i, 0));
    const T* b = row(std::min(y + i, h - 1));
    const float ki = k.w[i];
    for (int x = 0; x < w; ++x)
      out[x] += ki * (static_cast<float>(a[x]) + static_cast<float>(b[x]));
  }
}

// Horizontal pass of one row. `in` points at pixel 0 of a row padded with
// `radius` replicated pixels on both sides, so no read needs a clamp; `out`
// must not alias it.
KG_ALWAYS_INLINE void horizontal_row(const float* in, int w, const Kernel& k, float* out) {
  const int r = k.radius;
  const float k0 = k.w[0];
  for (int x = 0; x < w; ++x) out[x] = k0 * in[x];
  int i = 1;
  for (; i + 3 <= r; i += 4) {
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    const float kc = k.w[i + 2];
    const float kd = k.w[i + 3];
    for (int x = 0; x < w; ++x)
      out[x] += (ka * (in[x - i] + in[x + i]) + kb * (in[x - i - 1] + in[x + i + 1])) +
                (kc * (in[x - i - 2] + in[x + i + 2]) + kd * (in[x - i - 3] + in[x + i + 3]));
  }
  for (; i + 1 <= r; i += 2) {
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    for (int x = 0; x < w; ++x)
      out[x] += ka * (in[x - i] + in[x + i]) + kb * (in[x - i - 1] + in[x + i + 1]);
  }
  if (i <= r) {
    const float ki = k.w[i];
    for (int x = 0; x < w; ++x) out[x] += ki * (in[x - i] + in[x + i]);
  }
}

// Replicates the end pixels of the row [0, w) into its `radius` padding.
KG_ALWAYS_INLINE void pad_row(float* row, int w, int radius) {
  std::fill(row - radius, row, row[0]);
  std::fill(row + w, row + w + radius, row[w - 1]);
}

// The two image loops, compiled below for each dispatch level.
KG_ALWAYS_INLINE void blur_u8_rows(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst,
                                   float* vert, float* horz) {
  const int w = src.width;
  const int h = src.height;
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = 0; y < h; ++y) {
    vertical_row<std::uint8_t>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    horizontal_row(vert, w, k, horz);
    std::uint8_t* d = dst.row(y);
    for (int x = 0; x < w; ++x) {
      // Normalised weights keep the sum within [0, 255] up to rounding.
      const int v = static_cast<int>(horz[x] + 0.5f);
      d[x] = static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    }
  }
}

// Row by row (vertical into a padded buffer row, then horizontal straight
// into dst) so the source rows in use stay in cache.
KG_ALWAYS_INLINE void blur_float_rows(const Plane<float>& src, const Kernel& k, Plane<float>& dst,
                                      float* vert) {
  const int w = src.width();
  const int h = src.height();
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = 0; y < h; ++y) {
    vertical_row<float>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    horizontal_row(vert, w, k, dst.row(y));
  }
}

// The two loops for the baseline and (x86-64) AVX2; see core/support/simd_dispatch.h.
void blur_u8_baseline(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst, float* vert,
                      float* horz) {
  blur_u8_rows(src, k, dst, vert, horz);
}
void blur_float_baseline(const Plane<float>& src, const Kernel& k, Plane<float>& dst, float* vert) {
  blur_float_rows(src, k, dst, vert);
}
#if defined(KG_DISPATCH_AVX2)
KG_TARGET_AVX2 void blur_u8_avx2(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst,
                                 float* vert, float* horz) {
  blur_u8_rows(src, k, dst, vert, horz);
}
KG_TARGET_AVX2 void blur_float_avx2(const Plane<float>& src, const Kernel& k, Plane<float>& dst,
                                    float* vert) {
  blur_float_rows(src, k, dst, vert);
}
#endif

void blur_u8(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst, float* vert, float* horz) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return blur_u8_avx2(src, k, dst, vert, horz);
#endif
  blur_u8_baseline(src, k, dst, vert, horz);
}

void blur_float(const Plane<float>& src, const Kernel& k, Plane<float>& dst, float* vert) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return blur_float_avx2(src, k, dst, vert);
#endif
  blur_float_baseline(src, k, dst, vert);
}

}  // namespace

int blur_radius(float sigma) {
  const float r = std::ceil(3.f * sigma);
  return !(r > 0.f) ? 0 : r >= static_cast<float>(kMaxRadius) ? kMaxRadius : static_cast<int>(r);
}

void gaussian_blur(ImageView src, float sigma, Plane<std::uint8_t>& dst, Plane<float>& scratch) {
  if (src.empty()) {
    dst.resize(0, 0);
    return;
  }
  const int w = src.width;
  const int h = src.height;
  dst.resize(w, h);
  if (!(sigma > 0.f)) {
    for (int y = 0; y < h; ++y) std::memcpy(dst.row(y), src.row(y), static_cast<std::size_t>(w));
    return;
  }
  Kernel k;
  make_kernel(sigma, k);
  // Two row buffers: the padded vertical result, then the horizontal one
  // before rounding.
  const int padded = w + 2 * k.radius;
  scratch.resize(padded, 2);
  float* vert = scratch.row(0) + k.radius;
  float* horz = scratch.row(1);
  blur_u8(src, k, dst, vert, horz);
}

void gaussian_blur(const Plane<float>& src, float sigma, Plane<float>& dst, Plane<float>& scratch) {
  const int w = src.width();
  const int h = src.height();
  if (w <= 0 || h <= 0) {
    dst.resize(0, 0);
    return;
  }
  dst.resize(w, h);
  if (!(sigma > 0.f)) {
    for (int y = 0; y < h; ++y)
      std::memcpy(dst.row(y), src.row(y), static_cast<std::size_t>(w) * sizeof(float));
    return;
  }
  Kernel k;
  make_kernel(sigma, k);
  scratch.resize(w + 2 * k.radius, 1);
  float* vert = scratch.row(0) + k.radius;
  blur_float(src, k, dst, vert);
}

}  // namespace kg
