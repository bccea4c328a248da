#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <type_traits>

namespace kg {
namespace {

// Longest resampled profile accepted: bounds the stack buffers below.
constexpr int kMaxProfileLength = 256;
// The paper's l; its DFT table is built once, other lengths use a fallback.
constexpr int kTableLength = 30;
// A profile whose kept coefficients have a norm below this fraction of
// length * max|f| is flat: what is left is float rounding, not signal.
constexpr float kFlatTolerance = 1e-5f;
constexpr double kTwoPi = 6.283185307179586476925286766559;

struct DftTable {
  float cos[kMaxCoefficients][kTableLength];
  float sin[kMaxCoefficients][kTableLength];
};

const DftTable& table30() {
  static const DftTable table = [] {
    DftTable t{};
    for (int x = 0; x < kMaxCoefficients; ++x) {
      for (int y = 0; y < kTableLength; ++y) {
        // Reduce x*y mod l first so every entry is exactly periodic.
        const double angle = kTwoPi * ((x + 1) * y % kTableLength) / kTableLength;
        t.cos[x][y] = static_cast<float>(std::cos(angle));
        t.sin[x][y] = static_cast<float>(std::sin(angle));
      }
    }
    return t;
  }();
  return table;
}

// Rounds to the nearest pixel; false when that pixel is outside [0, size).
// Written so NaN and huge values fail the test before any conversion.
bool round_inside(float v, int size, int& out) {
  const float shifted = v + 0.5f;
  if (!(shifted >= 0.f && shifted < static_cast<float>(size))) return false;
  out = static_cast<int>(std::floor(shifted));
  return out < size;
}

}  // namespace

namespace {

// The rounded endpoints and axes of the Bresenham line from a to b, or
// false when the arc leaves the image (with the parallel offset) or is a
// single pixel.
struct ProfileLine {
  int ax, ay, bx, by, dx, dy, adx, ady, pdx, pdy, par;
  bool x_major;
};

bool profile_line(ImageView blurred, Point2f a, Point2f b, int parallel_offset, ProfileLine& l) {
  if (blurred.empty()) return false;
  if (!round_inside(a.x, blurred.width, l.ax) || !round_inside(a.y, blurred.height, l.ay) ||
      !round_inside(b.x, blurred.width, l.bx) || !round_inside(b.y, blurred.height, l.by)) {
    return false;
  }
  l.dx = l.bx - l.ax;
  l.dy = l.by - l.ay;
  l.adx = std::abs(l.dx);
  l.ady = std::abs(l.dy);
  if (l.adx == 0 && l.ady == 0) return false;

  // Major axis x when the line is more horizontal than vertical; the
  // parallel profiles are offset along the other (minor) axis.
  l.x_major = l.adx > l.ady;
  l.par = std::abs(parallel_offset);
  l.pdx = l.x_major ? 0 : l.par;
  l.pdy = l.x_major ? l.par : 0;
  // Every Bresenham pixel lies in the endpoints' bounding box, so one box
  // test widened by the parallel offset covers all three profiles.
  return !(std::min(l.ax, l.bx) - l.pdx < 0 || std::max(l.ax, l.bx) + l.pdx >= blurred.width ||
           std::min(l.ay, l.by) - l.pdy < 0 || std::max(l.ay, l.by) + l.pdy >= blurred.height);
}

}  // namespace

int profile_samples(ImageView blurred, Point2f a, Point2f b, int parallel_offset) {
  ProfileLine l;
  if (!profile_line(blurred, a, b, parallel_offset, l)) return 0;
  return std::max(l.adx, l.ady) + 1;
}

namespace {

// Walks the Bresenham line of `l` and hands each step t the sum of its
// three parallel pixels: store(t, sum).
template <class Store>
void walk_profile(ImageView blurred, const ProfileLine& l, Store store) {
  const int ax = l.ax, ay = l.ay, dx = l.dx, dy = l.dy, adx = l.adx, ady = l.ady, par = l.par;
  const bool x_major = l.x_major;
  const std::ptrdiff_t stride = blurred.stride;
  const std::ptrdiff_t sx = dx >= 0 ? 1 : -1;
  const std::ptrdiff_t sy = dy >= 0 ? stride : -stride;
  const std::ptrdiff_t major_step = x_major ? sx : sy;
  const std::ptrdiff_t minor_step = x_major ? sy : sx;
  const std::ptrdiff_t par_step = x_major ? par * stride : par;
  const bool minor_positive = (x_major ? dy : dx) > 0;
  const std::ptrdiff_t d = x_major ? adx : ady;   // Chebyshev length
  const std::ptrdiff_t dm = x_major ? ady : adx;  // |minor delta|

  // Minor offset at step t is t*dm/d rounded to nearest. rem tracks
  // (2*t*dm + d) mod 2d, so p sits on the round-half-up pixel and rem == 0
  // flags an exact half. Ties go toward the nearer endpoint, and the one at
  // the midpoint toward the smaller image coordinate: both are properties of
  // the segment, not of the walking direction, so b -> a visits exactly the
  // pixels of a -> b reversed.
  const std::uint8_t* p = blurred.row(ay) + ax;
  std::ptrdiff_t rem = d;
  const std::ptrdiff_t two_d = 2 * d;
  const std::ptrdiff_t two_dm = 2 * dm;
  // Steps t with 2t < half_limit send a tie toward a; half_limit = d + 1
  // puts the midpoint (2t == d) there too when the minor axis increases.
  const std::ptrdiff_t half_limit = minor_positive ? d + 1 : d;
  // Branch-free body (masks, not ?:, which compilers turn back into jumps):
  // a Bresenham line's minor steps are unpredictable for the branch predictor.
  for (std::ptrdiff_t t = 0; t <= d; ++t) {
    const std::ptrdiff_t back = -static_cast<std::ptrdiff_t>((rem == 0) & (2 * t < half_limit));
    const std::uint8_t* q = p - (minor_step & back);
    store(t, int{q[0]} + int{q[-par_step]} + int{q[par_step]});
    rem += two_dm;
    const std::ptrdiff_t carry = -static_cast<std::ptrdiff_t>(rem >= two_d);
    rem -= two_d & carry;
    p += major_step + (minor_step & carry);
  }
}

}  // namespace

bool mean_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset, float* out) {
  ProfileLine l;
  if (!profile_line(blurred, a, b, parallel_offset, l)) return false;
  constexpr float kThird = 1.f / 3.f;
  walk_profile(blurred, l,
               [out](std::ptrdiff_t t, int sum) { out[t] = static_cast<float>(sum) * kThird; });
  return true;
}

bool profile_sums(ImageView blurred, Point2f a, Point2f b, int parallel_offset, std::int32_t* out) {
  ProfileLine l;
  if (!profile_line(blurred, a, b, parallel_offset, l)) return false;
  walk_profile(blurred, l, [out](std::ptrdiff_t t, int sum) { out[t] = sum; });
  return true;
}

void resample_linear(const float* in, int n, float* out, int length) {
  if (length <= 0) return;
  if (n <= 0) {
    std::fill(out, out + length, 0.f);
    return;
  }
  if (n == 1 || length == 1) {
    std::fill(out, out + length, in[0]);
    return;
  }
  // Position i*(n-1)/L kept as integer j plus remainder r/L: no drift, the
  // last sample lands exactly on in[n-1], and the weights (L-r)/L and r/L are
  // mirror images for the reversed profile.
  const int last = length - 1;
  const float inv = 1.f / static_cast<float>(last);
  const int step = (n - 1) / last;
  const int step_rem = (n - 1) % last;
  int j = 0;
  int r = 0;
  for (int i = 0; i < length; ++i) {
    if (r == 0) {
      out[i] = in[j];
    } else {
      const float w1 = static_cast<float>(r) * inv;
      const float w0 = static_cast<float>(last - r) * inv;
      out[i] = w0 * in[j] + w1 * in[j + 1];
    }
    j += step;
    r += step_rem;
    if (r >= last) {
      r -= last;
      ++j;
    }
  }
}

namespace {

// Sub-pixel positions are integers in 1/16 pixel; a position farther out
// than this is refused before any conversion (no overflow below).
constexpr int kSubpixel = 16;
constexpr float kMaxSubpixelCoordinate = 1e6f;

// 256 times the bilinear sample at (x, y) in 1/16 pixel, inside the image
// with its right and lower neighbours (checked by the caller).
std::int32_t bilinear16(ImageView image, std::int64_t x, std::int64_t y) {
  const std::int64_t px = x / kSubpixel, py = y / kSubpixel;
  const auto u = static_cast<std::int32_t>(x - px * kSubpixel);
  const auto v = static_cast<std::int32_t>(y - py * kSubpixel);
  const std::uint8_t* r0 = image.row(static_cast<int>(py)) + px;
  const std::uint8_t* r1 = image.row(static_cast<int>(py) + 1) + px;
  return (kSubpixel - v) * ((kSubpixel - u) * r0[0] + u * r0[1]) +
         v * ((kSubpixel - u) * r1[0] + u * r1[1]);
}

// The samples a + (b - a) i / last, i = 0..last, rounded half up (every
// coordinate is >= 0 here), so b -> a rounds the same numerators: its
// profile is this one reversed. Last is a compile-time constant for the
// paper's length, which turns the divisions into multiplications.
template <class Last>
void sample_profile(ImageView image, std::int64_t ax, std::int64_t ay, std::int64_t dx,
                    std::int64_t dy, std::int64_t ox, std::int64_t oy, Last last,
                    std::int32_t* out) {
  const std::int64_t n = last;
  for (std::int64_t i = 0; i <= n; ++i) {
    const std::int64_t x = (2 * (ax * n + dx * i) + n) / (2 * n);
    const std::int64_t y = (2 * (ay * n + dy * i) + n) / (2 * n);
    out[i] = bilinear16(image, x, y) + bilinear16(image, x + ox, y + oy) +
             bilinear16(image, x - ox, y - oy);
  }
}

// Whether every sample of the three lines is inside: they lie in the box
// of the four ends, a and b each moved by +-(ox, oy), as a rounded point
// between two integers lies between them.
bool profile_inside(ImageView image, std::int64_t ax, std::int64_t ay, std::int64_t bx,
                    std::int64_t by, std::int64_t ox, std::int64_t oy) {
  const std::int64_t aox = std::abs(ox), aoy = std::abs(oy);
  const std::int64_t right = static_cast<std::int64_t>(image.width - 1) * kSubpixel;
  const std::int64_t bottom = static_cast<std::int64_t>(image.height - 1) * kSubpixel;
  return std::min(ax, bx) - aox >= 0 && std::min(ay, by) - aoy >= 0 &&
         std::max(ax, bx) + aox < right && std::max(ay, by) + aoy < bottom;
}

bool to_subpixel(float v, std::int64_t& out) {
  if (!(std::fabs(v) < kMaxSubpixelCoordinate)) return false;  // also NaN
  out = std::lround(static_cast<double>(v) * kSubpixel);
  return true;
}

}  // namespace

bool subpixel_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset, int length,
                      std::int32_t* out) {
  std::int64_t ax, ay, bx, by;
  if (blurred.empty() || length < 2 || !to_subpixel(a.x, ax) || !to_subpixel(a.y, ay) ||
      !to_subpixel(b.x, bx) || !to_subpixel(b.y, by))
    return false;
  const std::int64_t dx = bx - ax, dy = by - ay;
  if (dx == 0 && dy == 0) return false;
  // The perpendicular offset, rounded once per arc; each operation is a
  // single correctly rounded one on exact integers, so no core differs.
  const double norm = std::sqrt(static_cast<double>(dx * dx + dy * dy));
  const double offset = static_cast<double>(std::abs(parallel_offset) * kSubpixel);
  const std::int64_t ox = std::lround(static_cast<double>(-dy) * offset / norm);
  const std::int64_t oy = std::lround(static_cast<double>(dx) * offset / norm);
  if (!profile_inside(blurred, ax, ay, bx, by, ox, oy)) return false;
  if (length == 30) {
    sample_profile(blurred, ax, ay, dx, dy, ox, oy, std::integral_constant<std::int64_t, 29>{},
                   out);
  } else {
    sample_profile(blurred, ax, ay, dx, dy, ox, oy, std::int64_t{length - 1}, out);
  }
  return true;
}

bool subpixel_arc_descriptor(ImageView blurred, Point2f a, Point2f b,
                             const DescriptorParams& params, ArcDescriptor& out) {
  out.fill(0.f);
  const int length = params.profile_length;
  if (length < 2 || length > kMaxProfileLength) return false;
  std::int32_t sums[kMaxProfileLength];
  if (!subpixel_profile(blurred, a, b, params.parallel_offset, length, sums)) return false;
  float profile[kMaxProfileLength];
  constexpr float kToMean = 1.f / (3.f * kSubpixel * kSubpixel);
  for (int i = 0; i < length; ++i) profile[i] = static_cast<float>(sums[i]) * kToMean;
  return descriptor_from_profile(profile, length, params.coefficients, out);
}

bool descriptor_from_profile(const float* profile, int length, int coefficients,
                             ArcDescriptor& out) {
  out.fill(0.f);
  if (length < 2 || length > kMaxProfileLength || coefficients < 1 ||
      coefficients > kMaxCoefficients || coefficients >= length) {
    return false;
  }

  // F(0) is dropped anyway; removing the mean first keeps the float sums
  // small, so a brightness offset changes the result only in the last bits.
  float sum = 0.f;
  float max_abs = 0.f;
  for (int y = 0; y < length; ++y) {
    sum += profile[y];
    max_abs = std::max(max_abs, std::fabs(profile[y]));
  }
  const float mean = sum / static_cast<float>(length);
  float dev[kMaxProfileLength];
  for (int y = 0; y < length; ++y) dev[y] = profile[y] - mean;

  float re[kMaxCoefficients] = {};
  float im[kMaxCoefficients] = {};
  if (length == kTableLength) {
    // All kMaxCoefficients at once: six independent sums pipeline well, and
    // the unused ones cost less than a loop over a runtime count.
    const DftTable& t = table30();
    float c[kMaxCoefficients] = {};
    float s[kMaxCoefficients] = {};
    for (int y = 0; y < kTableLength; ++y) {
      for (int x = 0; x < kMaxCoefficients; ++x) {
        c[x] += dev[y] * t.cos[x][y];
        s[x] += dev[y] * t.sin[x][y];
      }
    }
    for (int x = 0; x < coefficients; ++x) {
      re[x] = c[x];
      im[x] = -s[x];
    }
  } else {
    float cos_k[kMaxProfileLength];
    float sin_k[kMaxProfileLength];
    for (int k = 0; k < length; ++k) {
      const double angle = kTwoPi * k / length;
      cos_k[k] = static_cast<float>(std::cos(angle));
      sin_k[k] = static_cast<float>(std::sin(angle));
    }
    for (int x = 1; x <= coefficients; ++x) {
      float c = 0.f, s = 0.f;
      int k = 0;  // x*y mod length
      for (int y = 0; y < length; ++y) {
        c += dev[y] * cos_k[k];
        s += dev[y] * sin_k[k];
        k += x;
        if (k >= length) k -= length;
      }
      re[x - 1] = c;
      im[x - 1] = -s;
    }
  }

  float energy = 0.f;
  for (int x = 0; x < coefficients; ++x) energy += re[x] * re[x] + im[x] * im[x];
  const float floor_norm = kFlatTolerance * static_cast<float>(length) * max_abs;
  if (!(energy > floor_norm * floor_norm)) return false;  // also rejects NaN and zero
  const float inv_norm = 1.f / std::sqrt(energy);
  for (int x = 0; x < coefficients; ++x) {
    out[2 * x] = re[x] * inv_norm;
    out[2 * x + 1] = im[x] * inv_norm;
  }
  return true;
}

bool descriptor_from_samples(const float* samples, int n, const DescriptorParams& params,
                             ArcDescriptor& out) {
  out.fill(0.f);
  const int length = params.profile_length;
  if (length < 2 || length > kMaxProfileLength || params.coefficients < 1 ||
      params.coefficients > kMaxCoefficients || params.coefficients >= length || n < 2) {
    return false;
  }
  float resampled[kMaxProfileLength];
  resample_linear(samples, n, resampled, length);
  return descriptor_from_profile(resampled, length, params.coefficients, out);
}

// --- Fixed point ------------------------------------------------------------

namespace {

// cos and sin of 2 pi k / 30 in Q28: mean deviations have at most 20 bits
// (30 * 29 * 765), 23 for sub-pixel profiles (30 * 256 * 765), so 30 terms
// stay below 2^56, and the table's rounding (2^-29) is far below an int16
// step (2^-15).
constexpr double kQ = 268435456.0;  // 2^28
struct FixedTable {
  std::int32_t cos[kMaxCoefficients][kTableLength];
  std::int32_t sin[kMaxCoefficients][kTableLength];
  // cos[x][l - y] == cos[x][y], sin[x][l - y] == -sin[x][y] and sin[x][0] ==
  // sin[x][l / 2] == 0 for every entry (true of the rounded values wherever
  // the C library's cos and sin are symmetric to within the rounding):
  // fixed_descriptor() then folds the profile and multiplies half as often,
  // with the same sums (integer arithmetic is exact in any order).
  bool symmetric = false;
  // The folded halves, 64-bit and interleaved by y for one pass over the
  // profile: half_cos[y][x] = cos[x][y] (y <= l / 2), half_sin[y][x] =
  // sin[x][y] (0 < y < l / 2).
  std::int64_t half_cos[kTableLength / 2 + 1][kMaxCoefficients];
  std::int64_t half_sin[kTableLength / 2][kMaxCoefficients];
};
static_assert(kTableLength % 2 == 0, "the fold pairs y with kTableLength - y");

const FixedTable& fixed_table30() {
  static const FixedTable table = [] {
    FixedTable t{};
    for (int x = 0; x < kMaxCoefficients; ++x) {
      for (int y = 0; y < kTableLength; ++y) {
        t.cos[x][y] = static_cast<std::int32_t>(
            std::lround(std::cos(kTwoPi * ((x + 1) * y % kTableLength) / kTableLength) * kQ));
        t.sin[x][y] = static_cast<std::int32_t>(
            std::lround(std::sin(kTwoPi * ((x + 1) * y % kTableLength) / kTableLength) * kQ));
      }
    }
    constexpr int kHalf = kTableLength / 2;
    t.symmetric = true;
    for (int x = 0; x < kMaxCoefficients; ++x) {
      t.symmetric = t.symmetric && t.sin[x][0] == 0 && t.sin[x][kHalf] == 0;
      for (int y = 1; y < kHalf; ++y)
        t.symmetric = t.symmetric && t.cos[x][kTableLength - y] == t.cos[x][y] &&
                      t.sin[x][kTableLength - y] == -t.sin[x][y];
      for (int y = 0; y <= kHalf; ++y) t.half_cos[y][x] = t.cos[x][y];
      for (int y = 0; y < kHalf; ++y) t.half_sin[y][x] = t.sin[x][y];
    }
    return t;
  }();
  return table;
}

// floor(sqrt(v)) for v < 2^63.
std::uint64_t isqrt(std::uint64_t v) {
  std::uint64_t r = static_cast<std::uint64_t>(std::sqrt(static_cast<double>(v)));
  while (r * r > v) --r;
  while ((r + 1) * (r + 1) <= v) ++r;
  return r;
}

int bit_length(std::uint64_t v) {
  return v == 0 ? 0 : 64 - __builtin_clzll(v);
}

}  // namespace

void resample_linear_fixed(const std::int32_t* in, int n, std::int32_t* out, int length) {
  if (length <= 0) return;
  const int last = length > 1 ? length - 1 : 1;
  if (n <= 0) {
    std::fill(out, out + length, 0);
    return;
  }
  if (n == 1 || length == 1) {
    std::fill(out, out + length, in[0] * last);
    return;
  }
  // resample_linear()'s walk, with the weights' common denominator kept.
  const int step = (n - 1) / last;
  const int step_rem = (n - 1) % last;
  // Branch-free: a weight r of 0 adds in[j + 1] * 0 (the same integer), and
  // before the last output j + 1 < n; the last output is in[n - 1] alone.
  int j = 0;
  int r = 0;
  for (int i = 0; i < last; ++i) {
    out[i] = in[j] * (last - r) + in[j + 1] * r;
    j += step;
    r += step_rem;
    const int carry = r >= last ? 1 : 0;
    r -= last & -carry;
    j += carry;
  }
  out[last] = in[n - 1] * last;
}

bool fixed_descriptor(const std::int32_t* profile, int length, int coefficients, std::int32_t scale,
                      std::int32_t* out) {
  for (int i = 0; i < kDescriptorSize; ++i) out[i] = 0;
  if (length != kTableLength || coefficients < 1 || coefficients > kMaxCoefficients || scale < 1)
    return false;
  // Deviations from the mean, times the length: exact integers.
  std::int64_t sum = 0;
  for (int y = 0; y < length; ++y) sum += profile[y];
  const FixedTable& t = fixed_table30();
  // With a symmetric table, dev[y] and dev[l - y] share their cos and
  // (negated) sin: their sum (even) and difference (odd) are multiplied
  // once, and computed from the profile directly.
  constexpr int kHalf = kTableLength / 2;
  std::int64_t dev[kTableLength];
  std::int64_t even[kHalf + 1];
  std::int64_t odd[kHalf];
  if (t.symmetric) {
    even[0] = std::int64_t{profile[0]} * kTableLength - sum;
    even[kHalf] = std::int64_t{profile[kHalf]} * kTableLength - sum;
    for (int y = 1; y < kHalf; ++y) {
      const std::int64_t a = profile[y], b = profile[kTableLength - y];
      even[y] = (a + b) * kTableLength - 2 * sum;
      odd[y] = (a - b) * kTableLength;
    }
  } else {
    for (int y = 0; y < length; ++y) dev[y] = std::int64_t{profile[y]} * length - sum;
  }
  // Every coefficient's sums in one pass (those past `coefficients` unused).
  static_assert(kMaxCoefficients == 3, "one accumulator per coefficient below");
  std::int64_t folded_re[kMaxCoefficients] = {};
  std::int64_t folded_im[kMaxCoefficients] = {};
  if (t.symmetric) {
    std::int64_t r0 = 0, r1 = 0, r2 = 0, i0 = 0, i1 = 0, i2 = 0;
    for (int y = 0; y <= kHalf; ++y) {
      const std::int64_t e = even[y];
      r0 += e * t.half_cos[y][0];
      r1 += e * t.half_cos[y][1];
      r2 += e * t.half_cos[y][2];
    }
    for (int y = 1; y < kHalf; ++y) {
      const std::int64_t o = odd[y];
      i0 -= o * t.half_sin[y][0];
      i1 -= o * t.half_sin[y][1];
      i2 -= o * t.half_sin[y][2];
    }
    folded_re[0] = r0;
    folded_re[1] = r1;
    folded_re[2] = r2;
    folded_im[0] = i0;
    folded_im[1] = i1;
    folded_im[2] = i2;
  }
  std::int64_t c[kDescriptorSize];
  std::uint64_t largest = 0;
  for (int x = 0; x < coefficients; ++x) {
    std::int64_t re = folded_re[x], im = folded_im[x];
    if (!t.symmetric) {
      for (int y = 0; y < length; ++y) {
        re += dev[y] * t.cos[x][y];
        im -= dev[y] * t.sin[x][y];
      }
    }
    c[2 * x] = re;
    c[2 * x + 1] = im;
    largest = std::max({largest, static_cast<std::uint64_t>(re < 0 ? -re : re),
                        static_cast<std::uint64_t>(im < 0 ? -im : im)});
  }
  if (largest == 0) return false;  // flat profile
  // Shift so that squares of the kept coefficients sum below 2^63.
  const int shift = std::max(0, bit_length(largest) - 30);
  std::uint64_t energy = 0;
  for (int i = 0; i < 2 * coefficients; ++i) {
    c[i] >>= shift;  // arithmetic: rounds toward minus infinity, alike for all
    energy += static_cast<std::uint64_t>(c[i] * c[i]);
  }
  const auto norm = static_cast<std::int64_t>(isqrt(energy));
  if (norm == 0) return false;
  // round(scale * c / norm), half away from zero, as quantise() rounds.
  for (int i = 0; i < 2 * coefficients; ++i) {
    const std::int64_t num = 2 * scale * (c[i] < 0 ? -c[i] : c[i]) + norm;
    std::int64_t q = num / (2 * norm);
    if (q > scale) q = scale;  // isqrt's floor can push a ratio past 1
    out[i] = static_cast<std::int32_t>(c[i] < 0 ? -q : q);
  }
  return true;
}

}  // namespace kg
