#include "core/keypoints/hessian.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/image/blur.h"
#include "core/support/simd_dispatch.h"
#include "core/support/strongest.h"

namespace kg {
namespace {

constexpr float kSigma0 = 1.6f;                  // first level of each octave (Lowe's SIFT value)
constexpr float kInputSigma = 0.5f;              // blur a camera image already has
constexpr int kBorder = 2;                       // det(H) reads 1 px around, the 3x3x3 test 1 more
constexpr double kMaxOffset = 0.6;               // larger refinement offsets: not a stable extremum
constexpr double kHalvingVariance = 1.0 / 16.0;  // 2x2 box, in the halved image's pixels

// Strongest first; ties by position so the order never depends on the scan.
bool stronger(const Keypoint& a, const Keypoint& b) {
  if (a.response != b.response) return a.response > b.response;
  if (a.y != b.y) return a.y < b.y;
  if (a.x != b.x) return a.x < b.x;
  return a.scale < b.scale;
}

void to_unit_float(ImageView image, Plane<float>& dst) {
  dst.resize(image.width, image.height);
  constexpr float kScale = 1.f / 255.f;
  for (int y = 0; y < image.height; ++y) {
    const std::uint8_t* s = image.row(y);
    float* d = dst.row(y);
    for (int x = 0; x < image.width; ++x) d[x] = kScale * static_cast<float>(s[x]);
  }
}

// Appends (x, y) of the pixels of row y (rows m0, m1, m2 around it) that
// are above the threshold, above their 8 neighbours in the level and, with
// the level below (rows l0, l1, l2 of its response), above the 9 there:
// all of the 3x3x3 test but the level above, which is not computed yet.
// It runs while the rows are in cache: done later per candidate, these
// reads missed the cache and the comparisons mispredicted, for the tens of
// thousands of candidates of a frame that fail them. The level test is
// branch-free so the compiler vectorises it; the few pixels that pass it
// take the level-below test one by one. Candidates beyond `limit` ints are
// dropped; returns false then.
KG_ALWAYS_INLINE bool collect_candidates(const float* m0, const float* m1, const float* m2,
                                         const float* l0, const float* l1, const float* l2, int y,
                                         int w, float thr, std::uint8_t* mask,
                                         WorkVector<std::int32_t>& cand, std::size_t limit) {
  for (int x = kBorder; x < w - kBorder; ++x) {
    const float v = m1[x];
    mask[x] = static_cast<std::uint8_t>((v > thr) & (v > m1[x - 1]) & (v >= m1[x + 1]) &
                                        (v > m0[x - 1]) & (v > m0[x]) & (v > m0[x + 1]) &
                                        (v >= m2[x - 1]) & (v >= m2[x]) & (v >= m2[x + 1]));
  }
  std::fill(mask + std::max(w - kBorder, 0), mask + w + 8, std::uint8_t{0});
  for (int x = kBorder; x < w - kBorder; ++x) {
    if ((x & 7) == 0) {  // skip 8 empty bytes at once
      std::uint64_t eight;
      std::memcpy(&eight, mask + x, sizeof eight);
      if (eight == 0) {
        x += 7;
        continue;
      }
    }
    if (!mask[x]) continue;
    const float v = m1[x];
    const bool below = (v > l0[x - 1]) & (v > l0[x]) & (v > l0[x + 1]) & (v > l1[x - 1]) &
                       (v > l1[x]) & (v > l1[x + 1]) & (v > l2[x - 1]) & (v > l2[x]) &
                       (v > l2[x + 1]);
    if (below) {
      if (cand.size() + 2 > limit) return false;
      cand.push_back(x);
      cand.push_back(y);
    }
  }
  return true;
}

// Scale-normalised sigma^4 (Lxx Lyy - Lxy^2) by central differences, for
// every pixel with all 8 neighbours; the 1-px frame is never read. With
// `cand`, also collects the level's extremum candidates while the rows are
// still in cache; `below` is then the response of the level below.
KG_ALWAYS_INLINE bool hessian_response_rows(const Plane<float>& L, float sigma, float threshold,
                                            Plane<float>& R, const Plane<float>* below,
                                            WorkVector<std::uint8_t>& mask,
                                            WorkVector<std::int32_t>* cand, std::size_t limit) {
  const int w = L.width();
  const int h = L.height();
  R.resize(w, h);
  if (cand) {
    cand->clear();
    mask.resize(static_cast<std::size_t>(w) + 8);  // +8: the skip reads 8 bytes at a time
  }
  const float norm = sigma * sigma * sigma * sigma;
  bool complete = true;
  for (int y = 1; y < h - 1; ++y) {
    const float* a = L.row(y - 1);
    const float* b = L.row(y);
    const float* c = L.row(y + 1);
    float* r = R.row(y);
    for (int x = 1; x < w - 1; ++x) {
      const float dxx = (b[x - 1] + b[x + 1]) - 2.f * b[x];
      const float dyy = (a[x] + c[x]) - 2.f * b[x];
      const float dxy = 0.25f * ((c[x + 1] - c[x - 1]) - (a[x + 1] - a[x - 1]));
      r[x] = norm * (dxx * dyy - dxy * dxy);
    }
    // Row y - 1 has both response neighbours now.
    if (cand && complete && y - 1 >= kBorder && y - 1 < h - kBorder)
      complete =
          collect_candidates(R.row(y - 2), R.row(y - 1), r, below->row(y - 2), below->row(y - 1),
                             below->row(y), y - 1, w, threshold, mask.data(), *cand, limit);
  }
  return complete;
}

// hessian_response_rows for the baseline and (x86-64) AVX2; see
// core/support/simd_dispatch.h.
bool hessian_response_baseline(const Plane<float>& L, float sigma, float threshold, Plane<float>& R,
                               const Plane<float>* below, WorkVector<std::uint8_t>& mask,
                               WorkVector<std::int32_t>* cand, std::size_t limit) {
  return hessian_response_rows(L, sigma, threshold, R, below, mask, cand, limit);
}
#if defined(KG_DISPATCH_AVX2)
KG_TARGET_AVX2 bool hessian_response_avx2(const Plane<float>& L, float sigma, float threshold,
                                          Plane<float>& R, const Plane<float>* below,
                                          WorkVector<std::uint8_t>& mask,
                                          WorkVector<std::int32_t>* cand, std::size_t limit) {
  return hessian_response_rows(L, sigma, threshold, R, below, mask, cand, limit);
}
#endif

bool hessian_response(const Plane<float>& L, float sigma, float threshold, Plane<float>& R,
                      const Plane<float>* below, WorkVector<std::uint8_t>& mask,
                      WorkVector<std::int32_t>* cand, std::size_t limit) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2)
    return hessian_response_avx2(L, sigma, threshold, R, below, mask, cand, limit);
#endif
  return hessian_response_baseline(L, sigma, threshold, R, below, mask, cand, limit);
}

// Halves the image by averaging 2x2 blocks (a trailing odd row or column is
// dropped). Output pixel x covers input pixels 2x and 2x + 1, so its centre
// is input 2x + 0.5: the half-pixel shift is undone when keypoints are mapped
// back. Averaging (unlike taking every other pixel) commutes with 90-degree
// rotations of even-sized images, and adds a variance of 1/16 in output
// pixels, which the caller accounts for. The source level has twice the
// octave's first sigma, so this does not alias.
void halve(const Plane<float>& src, Plane<float>& dst) {
  const int w = src.width() / 2;
  const int h = src.height() / 2;
  dst.resize(w, h);
  for (int y = 0; y < h; ++y) {
    const float* a = src.row(2 * y);
    const float* b = src.row(2 * y + 1);
    float* d = dst.row(y);
    for (int x = 0; x < w; ++x)
      d[x] = 0.25f * ((a[2 * x] + a[2 * x + 1]) + (b[2 * x] + b[2 * x + 1]));
  }
}

// Solves H o = -g (H symmetric 3x3) by Cramer's rule; false when singular.
bool solve_offset(const double H[3][3], const double g[3], double o[3]) {
  const double c00 = H[1][1] * H[2][2] - H[1][2] * H[2][1];
  const double c01 = H[1][2] * H[2][0] - H[1][0] * H[2][2];
  const double c02 = H[1][0] * H[2][1] - H[1][1] * H[2][0];
  const double det = H[0][0] * c00 + H[0][1] * c01 + H[0][2] * c02;
  if (!(std::fabs(det) > 0.0)) return false;
  const double inv[3][3] = {
      {c00, H[0][2] * H[2][1] - H[0][1] * H[2][2], H[0][1] * H[1][2] - H[0][2] * H[1][1]},
      {c01, H[0][0] * H[2][2] - H[0][2] * H[2][0], H[0][2] * H[1][0] - H[0][0] * H[1][2]},
      {c02, H[0][1] * H[2][0] - H[0][0] * H[2][1], H[0][0] * H[1][1] - H[0][1] * H[1][0]}};
  for (int i = 0; i < 3; ++i)
    o[i] = -(inv[i][0] * g[0] + inv[i][1] * g[1] + inv[i][2] * g[2]) / det;
  return std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]);
}

struct LevelInfo {
  int level;           // scale index inside the octave
  float octave_scale;  // 2^octave: octave pixels to input pixels
  float threshold;
  float sigma0;
  float log_k;  // log of the scale ratio between levels
};

// Local maxima of `mid` over its 26 neighbours in (lo, mid, hi), among the
// candidates collected with it (already above their 17 neighbours in lo and
// mid, so only hi is left to test); refined and offered to `out`. A plateau
// yields one maximum: values must be strictly above the neighbours before
// them in (scale, y, x) order, and at least equal to those after.
void scan_level(const WorkVector<std::int32_t>& cand, const Plane<float>& lo,
                const Plane<float>& mid, const Plane<float>& hi, const LevelInfo& info,
                int max_keypoints, WorkVector<Keypoint>& out) {
  for (std::size_t i = 0; i + 1 < cand.size(); i += 2) {
    const int x = cand[i];
    const int y = cand[i + 1];
    const float* m0 = mid.row(y - 1);
    const float* m1 = mid.row(y);
    const float* m2 = mid.row(y + 1);
    const float v = m1[x];
    const float* l0 = lo.row(y - 1);
    const float* l1 = lo.row(y);
    const float* l2 = lo.row(y + 1);
    const float* h0 = hi.row(y - 1);
    const float* h1 = hi.row(y);
    const float* h2 = hi.row(y + 1);
    // The level and the level below were tested when collecting.
    bool is_max = true;
    for (int dx = -1; dx <= 1 && is_max; ++dx)
      is_max = v >= h0[x + dx] && v >= h1[x + dx] && v >= h2[x + dx];
    if (!is_max) continue;

    // Quadratic fit in (x, y, scale) from central differences.
    const double c = v;
    const double g[3] = {0.5 * (static_cast<double>(m1[x + 1]) - m1[x - 1]),
                         0.5 * (static_cast<double>(m2[x]) - m0[x]),
                         0.5 * (static_cast<double>(h1[x]) - l1[x])};
    const double dxx = static_cast<double>(m1[x + 1]) + m1[x - 1] - 2.0 * c;
    const double dyy = static_cast<double>(m2[x]) + m0[x] - 2.0 * c;
    const double dss = static_cast<double>(h1[x]) + l1[x] - 2.0 * c;
    const double dxy = 0.25 * ((static_cast<double>(m2[x + 1]) - m2[x - 1]) -
                               (static_cast<double>(m0[x + 1]) - m0[x - 1]));
    const double dxs = 0.25 * ((static_cast<double>(h1[x + 1]) - h1[x - 1]) -
                               (static_cast<double>(l1[x + 1]) - l1[x - 1]));
    const double dys =
        0.25 * ((static_cast<double>(h2[x]) - h0[x]) - (static_cast<double>(l2[x]) - l0[x]));
    const double H[3][3] = {{dxx, dxy, dxs}, {dxy, dyy, dys}, {dxs, dys, dss}};
    double o[3];
    if (!solve_offset(H, g, o)) continue;
    if (std::fabs(o[0]) > kMaxOffset || std::fabs(o[1]) > kMaxOffset ||
        std::fabs(o[2]) > kMaxOffset)
      continue;
    Keypoint kp;
    // Octave pixel x has its centre at input (x + 0.5) 2^octave - 0.5 (see halve()).
    kp.x = static_cast<float>((x + o[0] + 0.5) * info.octave_scale - 0.5);
    kp.y = static_cast<float>((y + o[1] + 0.5) * info.octave_scale - 0.5);
    kp.scale = static_cast<float>(info.sigma0 * std::exp((info.level + o[2]) * info.log_k) *
                                  info.octave_scale);
    kp.response = static_cast<float>(c + 0.5 * (g[0] * o[0] + g[1] * o[1] + g[2] * o[2]));
    // Bounded memory however many extrema there are.
    offer_strongest(out, kp, static_cast<std::size_t>(std::max(0, max_keypoints)), stronger);
  }
}

}  // namespace

HessianDetector::HessianDetector(std::pmr::memory_resource* memory)
    : levels_{Plane<float>(memory), Plane<float>(memory)},
      responses_{Plane<float>(memory), Plane<float>(memory), Plane<float>(memory)},
      scratch_(memory),
      next_octave_(memory),
      mask_(memory),
      candidates_{WorkVector<std::int32_t>(memory), WorkVector<std::int32_t>(memory)},
      copy_(memory) {}

void HessianDetector::reserve(int max_width, int max_height, const KeypointParams& params,
                              int max_keypoints, int max_candidates) {
  for (Plane<float>& p : levels_) p.reserve(max_width, max_height);
  for (Plane<float>& p : responses_) p.reserve(max_width, max_height);
  next_octave_.reserve(max_width / 2, max_height / 2);
  // The widest blur is below the top level's total sigma.
  const int levels = std::max(1, params.hessian_levels);
  const int radius = blur_radius(
      static_cast<float>(kSigma0 * std::pow(2.0, static_cast<double>(levels + 1) / levels)));
  scratch_.reserve(max_width + 2 * radius, 1);
  mask_.reserve(static_cast<std::size_t>(max_width) + 8);
  max_candidate_ints_ = 2 * static_cast<std::size_t>(std::max(0, max_candidates));
  for (auto& c : candidates_) c.reserve(max_candidate_ints_);
  copy_.reserve(static_cast<std::size_t>(std::max(0, max_keypoints)));
}

void HessianDetector::detect(ImageView image, const KeypointParams& params, int max_keypoints,
                             std::vector<Keypoint>& out) {
  detect(image, params, max_keypoints, copy_);
  out.assign(copy_.begin(), copy_.end());
}

bool HessianDetector::detect(ImageView image, const KeypointParams& params, int max_keypoints,
                             WorkVector<Keypoint>& out) {
  out.clear();
  if (image.empty() || max_keypoints <= 0 || params.hessian_octaves <= 0) return true;
  bool complete = true;
  const int levels = std::max(1, params.hessian_levels);
  const double k = std::pow(2.0, 1.0 / levels);
  LevelInfo info;
  info.threshold = std::max(params.hessian_threshold, 0.f);  // maxima are always positive
  info.sigma0 = kSigma0;
  info.log_k = static_cast<float>(std::log(k));

  // Octave 0 starts at sigma0 from the input's assumed blur.
  to_unit_float(image, levels_[1]);
  gaussian_blur(levels_[1], std::sqrt(kSigma0 * kSigma0 - kInputSigma * kInputSigma), levels_[0],
                scratch_);
  const Plane<float>* first = &levels_[0];

  for (int octave = 0; octave < params.hessian_octaves; ++octave) {
    if (std::min(first->width(), first->height()) < 2 * kBorder + 3) break;
    info.octave_scale = std::ldexp(1.f, octave);
    const bool more = octave + 1 < params.hessian_octaves;
    // Level j has sigma0 k^j (octave pixels); levels 0 and levels + 1 exist
    // only as scale neighbours of levels 1..levels.
    // After octave 0 the first level also carries halve()'s box blur.
    const double first_sigma =
        octave == 0 ? kSigma0 : std::sqrt(kSigma0 * kSigma0 + kHalvingVariance);
    hessian_response(*first, static_cast<float>(first_sigma), info.threshold, responses_[0],
                     nullptr, mask_, nullptr, max_candidate_ints_);
    const Plane<float>* prev = first;
    for (int j = 1; j <= levels + 1; ++j) {
      const double s_prev = j == 1 ? first_sigma : kSigma0 * std::pow(k, j - 1);
      const double s_cur = kSigma0 * std::pow(k, j);
      Plane<float>& cur = levels_[j % 2];
      // Gaussians compose by adding variances: blur the previous level by the difference.
      gaussian_blur(*prev, static_cast<float>(std::sqrt(s_cur * s_cur - s_prev * s_prev)), cur,
                    scratch_);
      // Candidates only where maxima are taken: levels 1..levels.
      complete &=
          hessian_response(cur, static_cast<float>(s_cur), info.threshold, responses_[j % 3],
                           &responses_[(j - 1) % 3], mask_,
                           j <= levels ? &candidates_[j % 2] : nullptr, max_candidate_ints_);
      // Octave 0's first level lives in levels_[0], which level 2 overwrites,
      // so the next octave's first level goes to its own plane.
      if (j == levels && more) halve(cur, next_octave_);
      if (j >= 2) {
        info.level = j - 1;
        scan_level(candidates_[(j - 1) % 2], responses_[(j - 2) % 3], responses_[(j - 1) % 3],
                   responses_[j % 3], info, max_keypoints, out);
      }
      prev = &cur;
    }
    first = &next_octave_;
  }
  std::sort_heap(out.begin(), out.end(), stronger);
  return complete;
}

}  // namespace kg
