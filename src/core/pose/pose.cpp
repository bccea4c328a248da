#include "core/pose/pose.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/index/index_format.h"
#include "core/keygraphs/keygraph.h"
#include "core/pose/confidence.h"
#include "core/pose/homography.h"
#include "core/pose/ransac.h"

namespace kg {

namespace {

// Tolerance of the pre-test below: localisation noise plus a fraction of
// the distance over which a local affine map is extrapolated (perspective
// bends it), both in scene pixels.
constexpr float kPretestPixels = 3.f;
constexpr float kPretestFraction = 0.25f;

// Whether the affine map through the three correspondences (m0, s0)
// predicts the scene points s1 of the model points m1 (n of them) within
// the pre-test tolerance. Degenerate triangles fail.
bool affine_predicts(const Point2f* m0, const Point2f* s0, const Point2f* m1, const Point2f* s1,
                     int n) {
  const float m00 = m0[1].x - m0[0].x, m01 = m0[2].x - m0[0].x, m10 = m0[1].y - m0[0].y,
              m11 = m0[2].y - m0[0].y;
  const float det = m00 * m11 - m01 * m10;
  if (!(std::fabs(det) > 1e-3f)) return false;
  const float inv = 1.f / det;
  const float s00 = s0[1].x - s0[0].x, s01 = s0[2].x - s0[0].x, s10 = s0[1].y - s0[0].y,
              s11 = s0[2].y - s0[0].y;
  // A = S M^-1 maps model offsets from m0[0] to scene offsets from s0[0].
  const float a = (s00 * m11 - s01 * m10) * inv, b = (-s00 * m01 + s01 * m00) * inv;
  const float c = (s10 * m11 - s11 * m10) * inv, d = (-s10 * m01 + s11 * m00) * inv;
  const float cx = (s0[0].x + s0[1].x + s0[2].x) / 3.f, cy = (s0[0].y + s0[1].y + s0[2].y) / 3.f;
  for (int i = 0; i < n; ++i) {
    const float dx = m1[i].x - m0[0].x, dy = m1[i].y - m0[0].y;
    const float px = s0[0].x + a * dx + b * dy, py = s0[0].y + c * dx + d * dy;
    const float ex = px - s1[i].x, ey = py - s1[i].y;
    const float fx = s1[i].x - cx, fy = s1[i].y - cy;
    const float tol = kPretestPixels + kPretestFraction * std::sqrt(fx * fx + fy * fy);
    if (ex * ex + ey * ey > tol * tol) return false;
  }
  return true;
}

// Whether an instance with these corners repeats one of `model_id` already
// in `out`. A second RANSAC attempt on the left-over correspondences of one
// instance finds the same sign again, slightly shifted.
bool repeats_instance(const DetectionList& out, int model_id, const Point2f* corners) {
  for (const Detection& d : out) {
    if (d.model_id == model_id && outlines_overlap(d.corners, corners)) return true;
  }
  return false;
}

// View scale code (core/index/index_format.h) of a pose: the area scale of its
// local affine map at the model's centre, clamped to the codes' range (a
// scene larger than the model image is coded as the model's own scale).
int pose_view_code(const Homography& h, const ModelInfo& info) {
  const Point2f c{0.5f * (info.width - 1.f), 0.5f * (info.height - 1.f)};
  const Point2f o = kg::apply(h, c), x = kg::apply(h, {c.x + 1.f, c.y}),
                y = kg::apply(h, {c.x, c.y + 1.f});
  const double det = std::fabs(double{x.x - o.x} * (y.y - o.y) - double{x.y - o.y} * (y.x - o.x));
  if (!(det > 0.0) || !std::isfinite(det)) return 0;
  const double code = std::round(-0.5 * std::log2(det) * format::kViewCodesPerOctave);
  return static_cast<int>(std::clamp(code, 0.0, 255.0));
}

// Radius of the guided matching and the verification: the inlier
// threshold, shrunk for instances smaller than the model image (down to
// half of it at a quarter of the model's size). Keypoints of a small
// instance are fine-scale ones, localised to a pixel or two, while the
// chance of a hit grows with the radius squared: the full radius there
// lets chance hits swamp the verification.
float verification_radius(const RansacParams& rp, int code) {
  const double scale = std::exp2(-code / static_cast<double>(format::kViewCodesPerOctave));
  return static_cast<float>(rp.inlier_threshold * std::clamp(std::sqrt(scale), 0.5, 1.0));
}

// Whether the views detected model keypoint i near the scale of the pose
// (within half an octave of its finest or coarsest view): keypoints of
// fine detail do not exist in a small instance and only dilute the
// verification.
bool seen_at(const std::uint8_t* views, std::uint32_t i, int code) {
  constexpr int kMargin = 4;  // eighths of an octave
  return code >= views[2 * i] - kMargin && code <= views[2 * i + 1] + kMargin;
}

// Calls visit(i, p) for each model keypoint i that the pose's scale shows
// (seen_at) and that lands at p inside the frame under h, shifted by
// `offset` scene pixels, with the verification radius at that scale.
template <class Visit>
void for_each_shown_keypoint(const ModelIndex& index, const ModelInfo& info,
                             const FrameKeypoints& frame, const Homography& h, Point2f offset,
                             Visit&& visit) {
  const Point2f* model_points = index.keypoints() + info.keypoint_begin;
  const std::uint8_t* views = index.keypoint_views() + 2 * std::size_t{info.keypoint_begin};
  const int code = pose_view_code(h, info);
  const float radius = verification_radius(index.params().ransac, code);
  for (std::uint32_t i = 0; i < info.keypoint_count; ++i) {
    if (!seen_at(views, i, code)) continue;
    Point2f p = kg::apply(h, model_points[i]);
    p.x += offset.x;
    p.y += offset.y;
    if (!(p.x >= 0.f && p.y >= 0.f && p.x <= static_cast<float>(frame.width - 1) &&
          p.y <= static_cast<float>(frame.height - 1)))
      continue;
    visit(i, p, radius);
  }
}

double chance_fraction(const ModelIndex& index, const ModelInfo& info, const FrameKeypoints& frame,
                       const Homography& h) {
  // The same count under the pose shifted in the scene by a few inlier
  // thresholds: how often model keypoints land on frame keypoints by chance
  // in this part of the frame.
  const auto shift = static_cast<float>(3.0 * index.params().ransac.inlier_threshold);
  const Point2f offsets[4] = {{shift, 0.f}, {-shift, 0.f}, {0.f, shift}, {0.f, -shift}};
  int inside = 0, hits = 0;
  for (const Point2f& o : offsets) {
    for_each_shown_keypoint(index, info, frame, h, o, [&](std::uint32_t, Point2f p, float r) {
      ++inside;
      hits += frame.grid->nearest(p, r) >= 0 ? 1 : 0;
    });
  }
  return inside > 0 ? static_cast<double>(hits) / inside : 0.0;
}

// Binomial z-score of the fraction of `shown` model keypoints re-found
// against the fraction chance gives.
double support_z(double fraction, double chance, int shown) {
  const double spread = std::sqrt(std::max(1e-9, shown * chance * (1.0 - chance)));
  return (fraction - chance) * shown / spread;
}

}  // namespace

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

// RANSAC estimator over the active keygraph correspondences.
struct KeygraphEstimator {
  using Model = Homography;
  PoseEstimator& s;
  int k;
  int h;
  float model_w, model_h;
  const RansacParams& params;
  double min_area;  // smallest_area_scale() of the model
  double threshold2;

  int sample_count() const { return static_cast<int>(s.active_.size()); }
  int sample_size() const { return h; }

  bool hypothesis(const int* sample, Homography& out) {
    // Two circuits: each one's local affine map must predict the other's
    // points before the homography is fitted and scored. Rejects most
    // unrelated pairs for a few multiplications.
    if (h == 2 && k >= 3) {
      Point2f m[2][kMaxVertices], sc[2][kMaxVertices];
      for (int i = 0; i < 2; ++i) {
        const std::uint32_t* pairs =
            &s.match_pairs_[static_cast<std::size_t>(s.active_[sample[i]]) * k];
        for (int j = 0; j < k; ++j) {
          m[i][j] = s.pair_model_[pairs[j]];
          sc[i][j] = s.pair_scene_[pairs[j]];
        }
      }
      if (!affine_predicts(m[0], sc[0], m[1], sc[1], k) ||
          !affine_predicts(m[1], sc[1], m[0], sc[0], k))
        return false;
    }
    Point2f model[kMaxVertices * 4];
    Point2f scene[kMaxVertices * 4];
    std::uint32_t ids[kMaxVertices * 4];
    int n = 0;
    for (int i = 0; i < h; ++i) {
      const std::uint32_t* pairs =
          &s.match_pairs_[static_cast<std::size_t>(s.active_[sample[i]]) * k];
      for (int j = 0; j < k; ++j) {
        const std::uint32_t p = pairs[j];
        bool seen = false;
        for (int q = 0; q < n && !seen; ++q) seen = ids[q] == p;
        if (seen) continue;
        // One model keypoint may not go to two scene keypoints, nor two to one.
        const std::uint64_t key = s.pairs_[p];
        for (int q = 0; q < n; ++q) {
          const std::uint64_t other = s.pairs_[ids[q]];
          if ((other >> 32) == (key >> 32) || (other & 0xFFFFFFFFu) == (key & 0xFFFFFFFFu))
            return false;
        }
        ids[n] = p;
        model[n] = s.pair_model_[p];
        scene[n] = s.pair_scene_[p];
        ++n;
      }
    }
    if (n < 4) return false;
    if (!fit_homography_hypothesis(model, scene, n, out)) return false;
    return is_plausible_pose(out, model_w, model_h, params, min_area);
  }

  // Local optimisation (ransac.h): the least-squares homography through the
  // keypoint correspondences within `factor` times the inlier threshold of
  // `from` (those of instances already found excluded).
  bool fit_within(const Homography& from, double factor, Homography& out) {
    const double limit2 = threshold2 * factor * factor;
    s.inlier_model_.clear();
    s.inlier_scene_.clear();
    for (std::size_t i = 0; i < s.pairs_.size(); ++i) {
      if (s.pair_dead_[i]) continue;
      const Point2f p = kg::apply(from, s.pair_model_[i]);
      const double dx = p.x - s.pair_scene_[i].x, dy = p.y - s.pair_scene_[i].y;
      if (!(dx * dx + dy * dy < limit2)) continue;  // NaN too, as score() counts it
      s.inlier_model_.push_back(s.pair_model_[i]);
      s.inlier_scene_.push_back(s.pair_scene_[i]);
    }
    const int n = static_cast<int>(s.inlier_model_.size());
    return n >= 6 &&
           fit_homography_hypothesis(s.inlier_model_.data(), s.inlier_scene_.data(), n, out) &&
           is_plausible_pose(out, model_w, model_h, params, min_area);
  }

  // Whether the last scored model explains sample i (all its pairs inliers).
  bool sample_inlier(int i) const {
    const std::uint32_t* ids = &s.match_pairs_[static_cast<std::size_t>(s.active_[i]) * k];
    for (int j = 0; j < k; ++j)
      if (!s.pair_inlier_[ids[j]]) return false;
    return true;
  }

  RansacScore score(const Homography& hom) {
    RansacScore r;
    const std::size_t pairs = s.pairs_.size();
    for (std::size_t i = 0; i < pairs; ++i) {
      const Point2f p = kg::apply(hom, s.pair_model_[i]);
      const double dx = p.x - s.pair_scene_[i].x, dy = p.y - s.pair_scene_[i].y;
      const double e2 = dx * dx + dy * dy;
      const bool in = e2 < threshold2 && !s.pair_dead_[i];
      s.pair_inlier_[i] = in ? 1 : 0;
      r.point_inliers += in ? 1 : 0;
      r.cost += in ? e2 : threshold2;
    }
    for (int m : s.active_) {
      const std::uint32_t* ids = &s.match_pairs_[static_cast<std::size_t>(m) * k];
      bool all = true;
      for (int j = 0; j < k && all; ++j) all = s.pair_inlier_[ids[j]] != 0;
      r.sample_inliers += all ? 1 : 0;
    }
    return r;
  }
};

// The RANSAC loop's local optimisation needs fit_within (ransac.h); without
// it the loop would silently skip it.
static_assert(has_fit_within<KeygraphEstimator>::value);

PoseEstimator::PoseEstimator(std::pmr::memory_resource* memory)
    : pairs_(memory),
      pair_model_(memory),
      pair_scene_(memory),
      match_pairs_(memory),
      pair_inlier_(memory),
      pair_dead_(memory),
      match_active_(memory),
      pair_votes_(memory),
      match_quality_(memory),
      active_(memory),
      inlier_model_(memory),
      inlier_scene_(memory),
      guided_model_(memory),
      guided_scene_(memory),
      aligner_(memory) {}

void PoseEstimator::reserve(int max_matches, int k, std::uint32_t max_model_keypoints,
                            int max_appearance_pixels) {
  const auto n = static_cast<std::size_t>(std::max(0, max_matches));
  const std::size_t pairs = n * static_cast<std::size_t>(k);
  pairs_.reserve(pairs);
  pair_model_.reserve(pairs);
  pair_scene_.reserve(pairs);
  match_pairs_.reserve(pairs);
  pair_inlier_.reserve(pairs);
  pair_dead_.reserve(pairs);
  match_active_.reserve(n);
  pair_votes_.reserve(pairs);
  match_quality_.reserve(n);
  active_.reserve(n);
  inlier_model_.reserve(pairs);
  inlier_scene_.reserve(pairs);
  guided_model_.reserve(max_model_keypoints);
  guided_scene_.reserve(max_model_keypoints);
  aligner_.reserve(max_appearance_pixels);
}

PoseSupport measure_pose_support(const ModelIndex& index, int model_id, const FrameKeypoints& frame,
                                 const Homography& h) {
  PoseSupport support;
  if (model_id < 0 || model_id >= index.model_count() || frame.grid == nullptr) return support;
  const ModelInfo info = index.model(model_id);
  for_each_shown_keypoint(index, info, frame, h, {0.f, 0.f},
                          [&](std::uint32_t, Point2f p, float radius) {
                            ++support.shown;
                            support.refound += frame.grid->nearest(p, radius) >= 0 ? 1 : 0;
                          });
  if (support.shown == 0) return support;
  support.chance = chance_fraction(index, info, frame, h);
  support.z = support_z(static_cast<double>(support.refound) / support.shown, support.chance,
                        support.shown);
  return support;
}

PoseEstimator::Support PoseEstimator::guided_pairs(const ModelIndex& index, const ModelInfo& info,
                                                   const FrameKeypoints& frame,
                                                   const Homography& h) {
  const Point2f* model_points = index.keypoints() + info.keypoint_begin;
  guided_model_.clear();
  guided_scene_.clear();
  int inside = 0;
  for_each_shown_keypoint(index, info, frame, h, {0.f, 0.f},
                          [&](std::uint32_t i, Point2f p, float radius) {
                            ++inside;
                            const int j = frame.grid->nearest(p, radius);
                            if (j < 0) return;
                            guided_model_.push_back(model_points[i]);
                            guided_scene_.push_back({frame.keypoints[j].x, frame.keypoints[j].y});
                          });
  Support support;
  support.inside = inside;
  support.fraction = inside > 0 ? static_cast<double>(guided_model_.size()) / inside : 0.0;
  return support;
}

PoseEstimator::Support PoseEstimator::guided_refine(const ModelIndex& index, const ModelInfo& info,
                                                    const FrameKeypoints& frame, Homography& h) {
  const RansacParams& rp = index.params().ransac;
  Support support;
  for (int round = 0; round < 2; ++round) {
    support = guided_pairs(index, info, frame, h);
    if (guided_model_.size() < 8) break;
    Homography candidate = h;
    refine_homography(guided_model_.data(), guided_scene_.data(),
                      static_cast<int>(guided_model_.size()), candidate);
    if (!is_plausible_pose(candidate, info.width, info.height, rp,
                           smallest_area_scale(index.params(), info.width, info.height)))
      break;
    h = candidate;
  }
  return support;
}

int PoseEstimator::estimate(const ModelIndex& index, int model_id, const KeygraphMatch* matches,
                            int n, const Point2f* scene_points, const FrameKeypoints& frame,
                            Rng& rng, int max_out, DetectionList& out, bool& truncated) {
  const Params& params = index.params();
  const RansacParams& rp = params.ransac;
  const int k = vertex_count(params.graph.structure);
  const int h = sample_size(params.graph.structure);
  if (n < h) return 0;
  const ModelInfo info = index.model(model_id);
  const Point2f* model_points = index.keypoints();

  // Distinct keypoint correspondences (model id << 32 | scene index).
  pairs_.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      pairs_.push_back((static_cast<std::uint64_t>(matches[i].model_vertices[j]) << 32) |
                       static_cast<std::uint32_t>(matches[i].scene_vertices[j]));
    }
  }
  std::sort(pairs_.begin(), pairs_.end());
  pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
  const std::size_t pair_count = pairs_.size();
  pair_model_.resize(pair_count);
  pair_scene_.resize(pair_count);
  pair_inlier_.assign(pair_count, 0);
  pair_dead_.assign(pair_count, 0);
  for (std::size_t i = 0; i < pair_count; ++i) {
    pair_model_[i] = model_points[pairs_[i] >> 32];
    pair_scene_[i] = scene_points[pairs_[i] & 0xFFFFFFFFu];
  }
  match_pairs_.resize(static_cast<std::size_t>(n) * k);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      const std::uint64_t key = (static_cast<std::uint64_t>(matches[i].model_vertices[j]) << 32) |
                                static_cast<std::uint32_t>(matches[i].scene_vertices[j]);
      match_pairs_[static_cast<std::size_t>(i) * k + j] = static_cast<std::uint32_t>(
          std::lower_bound(pairs_.begin(), pairs_.end(), key) - pairs_.begin());
    }
  }
  match_active_.assign(static_cast<std::size_t>(n), 1);
  // ransac.progressive_sampling (format 6.4; 0, as in older files: uniform draws).
  const bool progressive = rp.progressive_sampling != 0;
  if (progressive) {
    // Each match's quality for progressive sampling: how often its keypoint
    // correspondences occur in other matches (once per shared pair). Correct circuits of one object
    // overlap (neighbouring triangles share edges in the model and the frame
    // alike); wrong ones rarely agree on a model keypoint for a frame one.
    pair_votes_.assign(pair_count, 0);
    for (std::uint32_t p : match_pairs_) ++pair_votes_[p];
    match_quality_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      int votes = 0;
      for (int j = 0; j < k; ++j)
        votes += pair_votes_[match_pairs_[static_cast<std::size_t>(i) * k + j]];
      match_quality_[static_cast<std::size_t>(i)] = votes - k;
    }
  }

  KeygraphEstimator estimator{*this,
                              k,
                              h,
                              info.width,
                              info.height,
                              rp,
                              smallest_area_scale(params, info.width, info.height),
                              rp.inlier_threshold * rp.inlier_threshold};
  RansacOptions options;
  options.confidence = rp.confidence;
  options.max_iterations = rp.max_iterations;
  options.enumerate_small_pools = true;
  // Correspondences ordered by shared pairs (above), PROSAC's schedule;
  // a prefix holding 16 inlier correspondences of the best pose may end the
  // search early (a floor of 4 or 8 stopped on wrong clusters of the sign
  // benchmark's small signs; docs/RESULTS.md, "Progressive sampling").
  options.progressive = progressive;
  options.prefix_min_sample_inliers = progressive ? 16 : 0;
  // The model's appearance, when the index and the frame allow aligning it;
  // poses it confirms may have less keypoint support.
  const ModelAppearance stored = index.appearance(model_id);
  const bool can_align = !stored.empty() && !frame.image.empty();
  const int least_inliers = can_align && rp.confirmed_min_inliers > 0
                                ? std::min(rp.min_inliers, rp.confirmed_min_inliers)
                                : rp.min_inliers;
  int iterations = 0;
  // Each attempt finds one instance or rules out one false cluster.
  for (int attempt = 0; attempt < rp.max_instances; ++attempt) {
    active_.clear();
    for (int i = 0; i < n; ++i) {
      if (match_active_[i]) active_.push_back(i);
    }
    if (static_cast<int>(active_.size()) < std::max(h, rp.min_inlier_keygraphs)) break;
    if (progressive) {
      // Best first (ties in selection order) for RansacOptions::progressive.
      std::sort(active_.begin(), active_.end(), [this](int a, int b) {
        const int qa = match_quality_[static_cast<std::size_t>(a)];
        const int qb = match_quality_[static_cast<std::size_t>(b)];
        return qa != qb ? qa > qb : a < b;
      });
    }
    Homography best{};
    const RansacStats stats = ransac(estimator, options, rng, best);
    iterations += stats.iterations;
    // The best cluster left cannot make an instance: neither can weaker ones.
    if (stats.best.point_inliers < least_inliers ||
        stats.best.sample_inliers < rp.min_inlier_keygraphs)
      break;

    // Refine on the inliers, re-selecting them with the refined pose.
    Homography refined = best;
    double rms = 0.0;
    RansacScore final_score = estimator.score(refined);
    for (int round = 0; round < 2; ++round) {
      inlier_model_.clear();
      inlier_scene_.clear();
      for (std::size_t i = 0; i < pair_count; ++i) {
        if (!pair_inlier_[i]) continue;
        inlier_model_.push_back(pair_model_[i]);
        inlier_scene_.push_back(pair_scene_[i]);
      }
      if (inlier_model_.size() < 4) break;
      Homography candidate = refined;
      rms = refine_homography(inlier_model_.data(), inlier_scene_.data(),
                              static_cast<int>(inlier_model_.size()), candidate);
      const RansacScore s = estimator.score(candidate);
      if (s.point_inliers < final_score.point_inliers) {
        estimator.score(refined);  // restore the inlier flags of the kept pose
        break;
      }
      refined = candidate;
      final_score = s;
    }

    // Guided refinement over all model keypoints, then the support that
    // the descriptors gave is recounted under the final pose.
    Support support = guided_refine(index, info, frame, refined);
    // Photometric refinement: the model's appearance aligned onto the frame
    // takes the corners from keypoint accuracy to sub-pixel, and its
    // correlation checks the identity (core/pose/appearance_align.h).
    double appearance = -1.0;  // -1: not measured
    if (can_align) {
      Homography aligned = refined;
      const AppearanceFit fit =
          aligner_.align({stored.pixels, stored.width, stored.height, stored.scale, stored.scale},
                         frame.image, aligned);
      if (fit.measured) {
        // The correlation of the pose kept; a negative one counts as none.
        const bool keep = fit.aligned && is_plausible_pose(aligned, info.width, info.height, rp,
                                                           estimator.min_area);
        appearance = std::max(0.0, keep ? fit.ncc : fit.ncc_before);
        if (keep) {
          refined = aligned;
          support = guided_pairs(index, info, frame, refined);
        }
      }
    }
    const double chance = chance_fraction(index, info, frame, refined);
    // Binomial z-score of the re-found model keypoints against chance.
    const double z = support_z(support.fraction, chance, support.inside);
    final_score = estimator.score(refined);

    // Distinct scene keypoints among the inliers (a scene point explained
    // twice counts once).
    int distinct = 0;
    {
      inlier_scene_.clear();
      for (std::size_t i = 0; i < pair_count; ++i) {
        if (pair_inlier_[i]) inlier_scene_.push_back(pair_scene_[i]);
      }
      std::sort(inlier_scene_.begin(), inlier_scene_.end(),
                [](Point2f a, Point2f b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
      for (std::size_t i = 0; i < inlier_scene_.size(); ++i) {
        if (i == 0 || inlier_scene_[i].x != inlier_scene_[i - 1].x ||
            inlier_scene_[i].y != inlier_scene_[i - 1].y)
          ++distinct;
      }
    }
    Point2f corners[4];
    for (int c = 0; c < 4; ++c) corners[c] = kg::apply(refined, info.outline[c]);
    // Enough keypoint support, and an appearance that does not contradict
    // it; or less support that the appearance confirms.
    const bool measured = appearance >= 0.0;
    const bool supported = distinct >= rp.min_inliers && z >= rp.min_verification_z &&
                           (!measured || appearance >= rp.min_appearance);
    const bool confirmed =
        measured && rp.confirmed_min_inliers > 0 && distinct >= rp.confirmed_min_inliers &&
        z >= rp.confirmed_min_verification_z && appearance >= rp.confirmed_min_appearance;
    const bool accepted =
        (supported || confirmed) && final_score.sample_inliers >= rp.min_inlier_keygraphs &&
        is_plausible_pose(refined, info.width, info.height, rp, estimator.min_area) &&
        !repeats_instance(out, model_id, corners);
    if (accepted && static_cast<int>(out.size()) >= max_out) {
      truncated = true;
      break;
    }
    if (accepted) {
      Detection d;
      d.model_id = model_id;
      d.model_name = info.name;
      d.homography = refined;
      for (int c = 0; c < 4; ++c) d.corners[c] = corners[c];
      d.inliers = distinct;
      d.inlier_keygraphs = final_score.sample_inliers;
      d.score = support.fraction;
      d.chance = chance;
      d.rms_error = rms;
      d.verification_z = z;
      d.appearance = appearance;
      d.confidence = detection_confidence(d);
      d.ransac_iterations = stats.iterations;
      out.push_back(d);
    }
    // Accepted or not, this cluster of correspondences is explained (by an
    // instance or as a false cluster); the next attempt looks elsewhere.
    // Remove every correspondence that touches this instance's inliers.
    for (int i : active_) {
      const std::uint32_t* ids = &match_pairs_[static_cast<std::size_t>(i) * k];
      for (int j = 0; j < k; ++j) {
        if (pair_inlier_[ids[j]]) {
          match_active_[i] = 0;
          break;
        }
      }
    }
    // Its keypoint correspondences no longer count for later instances.
    for (std::size_t i = 0; i < pair_count; ++i) {
      if (pair_inlier_[i]) pair_dead_[i] = 1;
      pair_inlier_[i] = 0;
    }
  }
  return iterations;
}

}  // namespace kg
