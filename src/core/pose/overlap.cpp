#include "core/pose/overlap.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include "core/keygraphs/keygraph.h"

namespace kg {

namespace {

// Whether p lies inside the convex quadrilateral q (either orientation).
bool inside_quad(const Point2f* q, Point2f p) {
  int positive = 0, negative = 0;
  for (int i = 0; i < 4; ++i) {
    const float turn = orient(q[i], q[(i + 1) % 4], p);
    positive += turn > 0.f ? 1 : 0;
    negative += turn < 0.f ? 1 : 0;
  }
  return positive == 0 || negative == 0;
}

Point2f centre_of(const Point2f* q) {
  return {(q[0].x + q[1].x + q[2].x + q[3].x) * 0.25f, (q[0].y + q[1].y + q[2].y + q[3].y) * 0.25f};
}

}  // namespace

bool outlines_overlap(const Point2f* a, const Point2f* b) {
  return inside_quad(a, centre_of(b)) || inside_quad(b, centre_of(a));
}

bool outlines_hold_each_other(const Point2f* a, const Point2f* b) {
  return inside_quad(a, centre_of(b)) && inside_quad(b, centre_of(a));
}

namespace {

// Difference of appearance correlations that decides between two models
// explaining the same part of the frame (a second instance of one model
// correlates alike).
constexpr double kClearlyBetterAppearance = 0.05;

bool clearly_better_appearance(const Detection& a, const Detection& b) {
  return a.appearance >= 0.0 && b.appearance >= 0.0 &&
         a.appearance - b.appearance > kClearlyBetterAppearance;
}

}  // namespace

void keep_best_of_overlapping(DetectionList& found) {
  // Greedy over a total order (more inliers, then the higher score over
  // chance, then the earlier detection): a candidate is kept when it
  // overlaps nothing kept, and replaces what it overlaps only when its
  // image matches clearly better than each of them (look-alike signs share
  // keypoints, not pixels). Replacements only raise the correlation, so
  // every group of overlapping detections keeps one.
  const std::size_t n = found.size();
  std::array<std::uint8_t, kMaxDetections> order{};
  std::array<bool, kMaxDetections> kept{};
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint8_t>(i);
  std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n),
            [&](std::uint8_t i, std::uint8_t j) {
              const Detection& a = found[i];
              const Detection& b = found[j];
              if (a.inliers != b.inliers) return a.inliers > b.inliers;
              const double margin_a = a.score - a.chance, margin_b = b.score - b.chance;
              if (margin_a != margin_b) return margin_a > margin_b;
              return i < j;
            });
  for (std::size_t r = 0; r < n; ++r) {
    const std::size_t c = order[r];
    bool overlaps = false, better_than_all = true;
    for (std::size_t k = 0; k < n; ++k) {
      if (!kept[k] || !outlines_overlap(found[c].corners, found[k].corners)) continue;
      overlaps = true;
      better_than_all = better_than_all && clearly_better_appearance(found[c], found[k]);
    }
    if (overlaps && !better_than_all) continue;
    for (std::size_t k = 0; k < n; ++k) {
      if (kept[k] && outlines_overlap(found[c].corners, found[k].corners)) kept[k] = false;
    }
    kept[c] = true;
  }
  std::size_t out = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (kept[i]) found[out++] = found[i];
  }
  found.truncate(out);
}

}  // namespace kg
