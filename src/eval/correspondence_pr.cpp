#include "eval/correspondence_pr.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "builder/image_io.h"
#include "builder/sift_descriptors.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/image/blur.h"
#include "core/image/plane.h"

namespace kg {

void CorrespondenceTruth::build(const std::vector<Point2f>& model, const Keypoint* scene,
                                int scene_count, const Homography& truth, double tolerance) {
  by_model_.assign(model.size(), {});
  scene_repeated_.assign(static_cast<std::size_t>(std::max(0, scene_count)), false);
  count_ = 0;
  // Scene keypoints bucketed on a grid of cells `tolerance` wide.
  const double cell = std::max(tolerance, 1.0);
  std::unordered_map<long long, std::vector<std::int32_t>> grid;
  const auto key = [](long long cx, long long cy) { return cx * 1000003LL + cy; };
  for (int s = 0; s < scene_count; ++s) {
    grid[key(static_cast<long long>(std::floor(scene[s].x / cell)),
             static_cast<long long>(std::floor(scene[s].y / cell)))]
        .push_back(s);
  }
  for (std::size_t m = 0; m < model.size(); ++m) {
    const Point2f p = kg::apply(truth, model[m]);
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    const auto cx = static_cast<long long>(std::floor(p.x / cell));
    const auto cy = static_cast<long long>(std::floor(p.y / cell));
    for (long long dy = -1; dy <= 1; ++dy) {
      for (long long dx = -1; dx <= 1; ++dx) {
        const auto it = grid.find(key(cx + dx, cy + dy));
        if (it == grid.end()) continue;
        for (const std::int32_t s : it->second) {
          if (std::hypot(double{scene[s].x} - p.x, double{scene[s].y} - p.y) < tolerance) {
            by_model_[m].push_back({s, count_++});
            scene_repeated_[static_cast<std::size_t>(s)] = true;
          }
        }
      }
    }
  }
}

long long CorrespondenceTruth::id(std::uint32_t m, std::int32_t s) const {
  if (m >= by_model_.size()) return -1;
  for (const Entry& e : by_model_[m]) {
    if (e.scene == s) return e.id;
  }
  return -1;
}

const std::vector<CorrespondenceTruth::Entry>& CorrespondenceTruth::of(std::uint32_t m) const {
  static const std::vector<Entry> none;
  return m < by_model_.size() ? by_model_[m] : none;
}

bool CorrespondenceTruth::scene_repeated(std::int32_t s) const {
  return s >= 0 && static_cast<std::size_t>(s) < scene_repeated_.size() &&
         scene_repeated_[static_cast<std::size_t>(s)];
}

cv::Mat blur_for_descriptors(const cv::Mat& gray, float sigma) {
  Plane<std::uint8_t> blurred;
  Plane<float> scratch;
  gaussian_blur(view_of(gray), sigma, blurred, scratch);
  return cv::Mat(blurred.height(), blurred.width(), CV_8UC1, blurred.data()).clone();
}

CaseCurve keygraph_curve(const BuiltModel& model, std::uint32_t keypoint_begin,
                         const cv::Mat& blurred, const Keypoint* scene, int scene_count,
                         const std::vector<KeygraphMatch>& matches, int model_id,
                         const Params& params, const CorrespondenceTruth& truth,
                         const std::vector<double>& thresholds) {
  CurveBuilder curve(thresholds, truth.count());
  const ImageView view = view_of(blurred);
  const int k = static_cast<int>(params.graph.structure);
  const int arcs = k == 2 ? 1 : k;
  // Scene arc descriptors, each computed once (NaN distance when invalid).
  std::unordered_map<std::uint64_t, std::pair<bool, ArcDescriptor>> scene_arcs;
  std::vector<float> scratch;
  const auto scene_arc = [&](std::int32_t a,
                             std::int32_t b) -> const std::pair<bool, ArcDescriptor>& {
    const std::uint64_t key = static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32 |
                              static_cast<std::uint32_t>(b);
    auto it = scene_arcs.find(key);
    if (it != scene_arcs.end()) return it->second;
    std::pair<bool, ArcDescriptor> d{false, {}};
    if (a >= 0 && b >= 0 && a < scene_count && b < scene_count)
      d.first = arc_descriptor(view, {scene[a].x, scene[a].y}, {scene[b].x, scene[b].y},
                               params.descriptor, scratch, d.second);
    return scene_arcs.emplace(key, d).first->second;
  };
  // The distance to the most similar of the model's arcs from a to b (views
  // may describe one pair several times); NaN when there is none.
  const std::int32_t box = attribute_box(params.graph);
  const auto model_arc_distance = [&](std::uint32_t a, std::uint32_t b, const ArcDescriptor& d,
                                      const float* attributes) {
    const auto range =
        std::equal_range(model.arcs.begin(), model.arcs.end(), ModelArc{a, b},
                         [](const ModelArc& x, const ModelArc& y) {
                           return x.from < y.from || (x.from == y.from && x.to < y.to);
                         });
    double best = std::numeric_limits<double>::quiet_NaN();
    for (auto it = range.first; it != range.second; ++it) {
      const auto i = static_cast<std::size_t>(it - model.arcs.begin());
      // As the search: the scale attributes within the box, then the descriptor.
      if (box > 0 && attributes != nullptr && i < model.arc_attributes.size() &&
          (std::fabs(model.arc_attributes[i][0] - attributes[0]) > static_cast<float>(box) ||
           std::fabs(model.arc_attributes[i][1] - attributes[1]) > static_cast<float>(box)))
        continue;
      const double e = std::sqrt(double{squared_distance(model.descriptors[i], d)});
      if (!(e >= best)) best = e;
    }
    return best;
  };
  for (const KeygraphMatch& match : matches) {
    if (match.model_id != model_id) continue;
    std::uint32_t mv[4];
    bool valid = true;
    for (int v = 0; v < k; ++v) {
      valid = valid && match.model_vertices[v] >= keypoint_begin;
      mv[v] = match.model_vertices[v] - keypoint_begin;
    }
    double worst = valid ? 0.0 : std::numeric_limits<double>::quiet_NaN();
    for (int e = 0; valid && e < arcs; ++e) {
      const int a = e, b = (e + 1) % k;
      const auto& sd = scene_arc(match.scene_vertices[a], match.scene_vertices[b]);
      float attributes[kArcAttributes];
      const Keypoint& sa = scene[match.scene_vertices[a]];
      const Keypoint& sb = scene[match.scene_vertices[b]];
      const bool scaled =
          arc_attributes({sa.x, sa.y}, {sb.x, sb.y}, sa.scale, sb.scale, attributes);
      const double distance =
          sd.first ? model_arc_distance(mv[a], mv[b], sd.second, scaled ? attributes : nullptr)
                   : std::nan("");
      if (std::isnan(distance)) {
        worst = distance;
        break;
      }
      worst = std::max(worst, distance);
    }
    bool correct = true;
    long long ids[4] = {-1, -1, -1, -1};
    for (int v = 0; v < k; ++v) {
      ids[v] = truth.id(mv[v], match.scene_vertices[v]);
      correct = correct && ids[v] >= 0;
    }
    curve.add(worst, correct);
    if (std::isnan(worst)) continue;
    for (int v = 0; v < k; ++v) curve.reach(ids[v], worst);
  }
  return curve.finish();
}

cv::Mat unit_sift(const cv::Mat& gray, const std::vector<Keypoint>& keypoints) {
  SiftDescriber sift;
  std::vector<std::uint8_t> bytes;
  const int n = static_cast<int>(keypoints.size());
  sift.describe(gray, keypoints.data(), n, bytes);
  cv::Mat out(n, kVertexDescriptorSize, CV_32F);
  for (int i = 0; i < n; ++i) {
    float* row = out.ptr<float>(i);
    double norm2 = 0;
    for (int j = 0; j < kVertexDescriptorSize; ++j) {
      row[j] = bytes[static_cast<std::size_t>(i * kVertexDescriptorSize + j)];
      norm2 += double{row[j]} * row[j];
    }
    const float inv = norm2 > 0 ? static_cast<float>(1.0 / std::sqrt(norm2)) : 0.f;
    for (int j = 0; j < kVertexDescriptorSize; ++j) row[j] *= inv;
  }
  return out;
}

void keypoint_curves(const cv::Mat& model_sift, const cv::Mat& scene_sift,
                     const CorrespondenceTruth& truth, const std::vector<double>& distance_grid,
                     const std::vector<double>& ratio_grid, CaseCurve& by_distance,
                     CaseCurve& by_ratio) {
  CurveBuilder distance(distance_grid, truth.count());
  CurveBuilder ratio(ratio_grid, truth.count());
  if (!model_sift.empty() && !scene_sift.empty()) {
    // Squared distances |m|^2 + |s|^2 - 2 m.s through one matrix product.
    cv::Mat dot;
    cv::gemm(model_sift, scene_sift, 1.0, cv::noArray(), 0.0, dot, cv::GEMM_2_T);
    std::vector<float> scene_norm2(static_cast<std::size_t>(scene_sift.rows));
    for (int s = 0; s < scene_sift.rows; ++s)
      scene_norm2[static_cast<std::size_t>(s)] =
          static_cast<float>(scene_sift.row(s).dot(scene_sift.row(s)));
    std::vector<long long> row_truth(static_cast<std::size_t>(scene_sift.rows), -1);
    for (int m = 0; m < model_sift.rows; ++m) {
      const float model_norm2 = static_cast<float>(model_sift.row(m).dot(model_sift.row(m)));
      const auto& true_pairs = truth.of(static_cast<std::uint32_t>(m));
      for (const auto& e : true_pairs) row_truth[static_cast<std::size_t>(e.scene)] = e.id;
      const float* row = dot.ptr<float>(m);
      double best = std::numeric_limits<double>::infinity(), second = best;
      int best_s = -1;
      for (int s = 0; s < scene_sift.rows; ++s) {
        const double d = std::sqrt(std::max(
            0.0, double{model_norm2} + scene_norm2[static_cast<std::size_t>(s)] - 2.0 * row[s]));
        const long long id = row_truth[static_cast<std::size_t>(s)];
        distance.add(d, id >= 0);
        if (id >= 0) distance.reach(id, d);
        if (d < best) {
          second = best;
          best = d;
          best_s = s;
        } else if (d < second) {
          second = d;
        }
      }
      if (best_s >= 0 && std::isfinite(second)) {
        const double r = second > 0 ? best / second : 1.0;
        const long long id = row_truth[static_cast<std::size_t>(best_s)];
        ratio.add(r, id >= 0);
        if (id >= 0) ratio.reach(id, r);
      }
      for (const auto& e : true_pairs) row_truth[static_cast<std::size_t>(e.scene)] = -1;
    }
  }
  by_distance = distance.finish();
  by_ratio = ratio.finish();
}

}  // namespace kg
