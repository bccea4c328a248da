#include "core/triangle_patch.h"

#include <algorithm>
#include <cmath>

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

// Bilinear sample; false outside [0, width - 1) x [0, height - 1).
bool sample(const std::uint8_t* pixels, int width, int height, std::ptrdiff_t stride, float x,
            float y, float& value) {
  if (!(x >= 0.f && y >= 0.f && x < static_cast<float>(width - 1) &&
        y < static_cast<float>(height - 1)))
    return false;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const std::uint8_t* r0 = pixels + static_cast<std::ptrdiff_t>(y0) * stride + x0;
  const std::uint8_t* r1 = r0 + stride;
  const float top = r0[0] + fx * static_cast<float>(r0[1] - r0[0]);
  const float bottom = r1[0] + fx * static_cast<float>(r1[1] - r1[0]);
  value = top + fy * (bottom - top);
  return true;
}

// The mean of sub x sub samples spaced `step` apart around (x, y).
bool averaged(const std::uint8_t* pixels, int width, int height, std::ptrdiff_t stride, float x,
              float y, int sub, float step, float& value) {
  if (sub == 1) return sample(pixels, width, height, stride, x, y, value);
  const float first = -0.5f * step * static_cast<float>(sub - 1);
  float sum = 0.f;
  for (int j = 0; j < sub; ++j) {
    for (int i = 0; i < sub; ++i) {
      float v;
      if (!sample(pixels, width, height, stride, x + first + step * static_cast<float>(i),
                  y + first + step * static_cast<float>(j), v))
        return false;
      sum += v;
    }
  }
  value = sum / static_cast<float>(sub * sub);
  return true;
}

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
  const Point2f ca{(a[0].x + a[1].x + a[2].x) / 3.f, (a[0].y + a[1].y + a[2].y) / 3.f};
  const Point2f cf{(scene[0].x + scene[1].x + scene[2].x) / 3.f,
                   (scene[0].y + scene[1].y + scene[2].y) / 3.f};
  float ta[kTriangleSamples], tf[kTriangleSamples], lu[kTriangleSamples], lv[kTriangleSamples];
  int n = 0;
  const float inv_steps = 1.f / static_cast<float>(kLatticeSteps);
  for (int i = 0; i <= kLatticeSteps; ++i) {
    for (int j = 0; i + j <= kLatticeSteps; ++j) {
      // Barycentric (l0, l1, l2) of the enlarged triangle about the centroid.
      const float l0 = static_cast<float>(i) * inv_steps - 1.f / 3.f;
      const float l1 = static_cast<float>(j) * inv_steps - 1.f / 3.f;
      const float l2 = -l0 - l1;
      const float xa = ca.x + kEnlarge * (l0 * a[0].x + l1 * a[1].x + l2 * a[2].x);
      const float ya = ca.y + kEnlarge * (l0 * a[0].y + l1 * a[1].y + l2 * a[2].y);
      const float xf = cf.x + kEnlarge * (l0 * scene[0].x + l1 * scene[1].x + l2 * scene[2].x);
      const float yf = cf.y + kEnlarge * (l0 * scene[0].y + l1 * scene[1].y + l2 * scene[2].y);
      float va, vf;
      if (!averaged(appearance.pixels, appearance.width, appearance.height, appearance.width, xa,
                    ya, sub_a, step_a, va) ||
          !averaged(frame.data, frame.width, frame.height, frame.stride, xf, yf, sub_f, step_f, vf))
        continue;
      lu[n] = l0;
      lv[n] = l1;
      ta[n] = va;
      tf[n] = vf;
      ++n;
    }
  }
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
