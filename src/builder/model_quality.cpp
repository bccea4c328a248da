#include "builder/model_quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/in_memory_index.h"
#include "builder/parallel.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_types.h"
#include "core/index/kdtree.h"

namespace kg {

namespace {

std::uint32_t saturate_u32(std::uint64_t v) {
  return static_cast<std::uint32_t>(std::min<std::uint64_t>(v, 0xFFFFFFFFu));
}

// Long edge in frame pixels of the smallest frontal view, going down from
// the model's own size, before the first view that lacks the keypoints or
// keygraphs of a detection (0 when the largest already lacks them).
float smallest_size(const BuiltModel& model, const Params& params) {
  const auto enough_keypoints =
      static_cast<std::uint64_t>(kViewKeypointFactor * params.ransac.min_inliers);
  const auto enough_keygraphs =
      static_cast<std::uint64_t>(kViewKeygraphFactor * params.ransac.min_inlier_keygraphs);
  float smallest = 0.f;
  // The frontal pyramid comes first, largest first; then tilted views, then
  // (views.max_scale) views larger than the model image.
  for (const ViewSummary& v : model.views) {
    if (v.blur > 0.0 || v.glow) continue;  // the sharp view before it judges the size
    if (v.tilt != 1.0 || v.scale > 1.0) break;
    if (static_cast<std::uint64_t>(v.keypoints) < enough_keypoints ||
        v.keygraphs < enough_keygraphs)
      break;
    smallest = static_cast<float>(std::max(v.width, v.height));
  }
  return smallest;
}

// Per model, how many of its arcs have a near-identical arc (descriptor
// within kNearIdenticalDistance, attributes within the search box) in
// another model: exact radius searches in a float tree over every arc of
// the index, from at most kSharedSample evenly spaced arcs of each model,
// the count scaled to all its arcs. Searching from every arc took minutes
// once tilted views gave a sign 78 k to 166 k arcs; the estimate's
// standard error is under 1 % of the model's arcs.
std::vector<std::uint32_t> shared_arcs(const std::vector<BuiltModel>& models, const Params& params,
                                       int threads) {
  std::vector<ArcSearchPoint> source;
  std::vector<std::uint32_t> owner;
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    for (std::size_t a = 0; a < model.arcs.size(); ++a) {
      std::array<float, 2> attributes{0.f, 0.f};
      if (model.arc_attributes.size() == model.arcs.size()) attributes = model.arc_attributes[a];
      source.push_back(search_point(model.descriptors[a], attributes.data()));
      owner.push_back(static_cast<std::uint32_t>(m));
    }
  }
  std::vector<std::uint32_t> shared(models.size(), 0);
  if (source.empty() || models.size() < 2) return shared;
  std::vector<ArcSearchPoint> points;
  std::vector<std::uint32_t> ids;
  std::vector<KdNode> nodes;
  const auto n = static_cast<std::uint32_t>(source.size());
  const float radius = kNearIdenticalDistance;
  const float box = static_cast<float>(attribute_box(params.graph));
  // Attributes split as often as descriptor components (as in the index's
  // tree), and leaf bounds so that a search skips most leaves.
  build_kdtree<float, kSearchDims>(source.data(), n, points, ids, nodes,
                                   box > 0.f ? 0.5 * radius / box : 0.0);
  std::vector<ArcSearchPoint> bounds;
  kdtree_leaf_bounds<float, kSearchDims>(points.data(), n, bounds);
  const ArcTreeView tree(points.data(), ids.data(), n, nodes.data(), kdtree_depth(n),
                         bounds.data());
  std::vector<std::uint32_t> first_arc(models.size(), 0);  // the model's first arc in `source`
  for (std::size_t m = 1; m < models.size(); ++m)
    first_arc[m] = first_arc[m - 1] + static_cast<std::uint32_t>(models[m - 1].arcs.size());
  // The models' searches are independent reads of one tree.
  parallel_for(models.size(), threads, [&](std::size_t m) {
    std::vector<std::uint32_t> found(256);
    const std::uint32_t begin = first_arc[m];
    const auto arcs = static_cast<std::uint32_t>(models[m].arcs.size());
    const std::uint32_t stride =
        std::max<std::uint32_t>(1, arcs / kSharedSample + (arcs % kSharedSample != 0 ? 1 : 0));
    std::uint32_t searched = 0, near_identical = 0;
    for (std::uint32_t i = begin; i < begin + arcs; i += stride) {
      ++searched;
      std::uint32_t count = 0;
      for (;;) {
        count = box > 0.f ? tree.radius_search(source[i], radius * radius, box, found.data(),
                                               static_cast<std::uint32_t>(found.size()))
                          : tree.radius_search(source[i], radius * radius, found.data(),
                                               static_cast<std::uint32_t>(found.size()));
        if (count <= found.size()) break;
        found.resize(count);
      }
      for (std::uint32_t k = 0; k < count; ++k) {
        if (owner[found[k]] != m) {
          ++near_identical;
          break;
        }
      }
    }
    if (searched > 0)
      shared[m] = static_cast<std::uint32_t>(
          std::llround(static_cast<double>(near_identical) * arcs / searched));
    return true;
  });
  return shared;
}

}  // namespace

cv::Mat render_quality_scene(const cv::Mat& gray, int long_edge, cv::Point2f outline[4]) {
  const double k = std::min(1.0, static_cast<double>(long_edge) / std::max(gray.cols, gray.rows));
  const int w = std::max(1, static_cast<int>(std::lround(gray.cols * k)));
  const int h = std::max(1, static_cast<int>(std::lround(gray.rows * k)));
  cv::Mat scaled;
  if (k < 1.0) {
    cv::resize(gray, scaled, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  } else {
    scaled = gray;
  }
  // A margin of mid-grey (flat: no keypoints of its own), and the right
  // edge 12 % shorter than the left: a sign seen about 20 degrees from the
  // side.
  const int margin = std::max(24, std::max(w, h) / 5);
  cv::Mat scene(h + 2 * margin, w + 2 * margin, CV_8UC1, cv::Scalar(128));
  const float squeeze = 0.06f * static_cast<float>(h);
  const cv::Point2f from[4] = {{0.f, 0.f},
                               {static_cast<float>(w), 0.f},
                               {static_cast<float>(w), static_cast<float>(h)},
                               {0.f, static_cast<float>(h)}};
  const auto m = static_cast<float>(margin);
  outline[0] = {m, m};
  outline[1] = {m + static_cast<float>(w), m + squeeze};
  outline[2] = {m + static_cast<float>(w), m + static_cast<float>(h) - squeeze};
  outline[3] = {m, m + static_cast<float>(h)};
  const cv::Mat to_scene = cv::getPerspectiveTransform(from, outline);
  cv::warpPerspective(scaled, scene, to_scene, scene.size(), cv::INTER_LINEAR,
                      cv::BORDER_TRANSPARENT);
  return scene;
}

Status measure_quality(const std::vector<BuiltModel>& models, const std::vector<cv::Mat>& grays,
                       const Params& params, const QualityOptions& options, QualityReport& out) {
  if (grays.size() != models.size())
    return {StatusCode::kInvalidArgument, "quality: one model image per model expected"};
  out = QualityReport{};
  const std::vector<std::uint32_t> shared = shared_arcs(models, params, options.threads);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    ModelQuality q;
    q.view_begin = static_cast<std::uint32_t>(out.views.size());
    q.shared_arcs = shared[m];
    q.smallest_size = smallest_size(model, params);
    // The blurred and glowing twins of small views (ViewParams::
    // blurred_max_size, glow_max_size) are not stored: the format has no field to tell them from
    // their sharp view; their arcs are in the model's.
    for (const ViewSummary& v : model.views) {
      if (v.blur > 0.0 || v.glow) continue;
      ViewQuality vq;
      vq.scale = static_cast<float>(v.scale);
      vq.tilt = static_cast<float>(v.tilt);
      vq.longitude = static_cast<float>(v.longitude);
      vq.keypoints = static_cast<std::uint32_t>(std::max(v.keypoints, 0));
      vq.arcs = static_cast<std::uint32_t>(std::max(v.view_arcs, 0));
      vq.keygraphs = saturate_u32(v.keygraphs);
      out.views.push_back(vq);
    }
    q.view_count = static_cast<std::uint32_t>(out.views.size()) - q.view_begin;
    out.models.push_back(q);
  }
  if (!options.look_alikes) return Status::ok();

  InMemoryIndex index;
  if (Status s = index.build(models, params); !s) return s;
  // Each model's scene on its own detector (the index is only read); the
  // results are gathered in model order.
  std::vector<std::vector<std::uint32_t>> others(models.size());
  const Status checked = parallel_for_status(models.size(), options.threads, [&](std::size_t m) {
    cv::Point2f outline[4];
    const cv::Mat scene = render_quality_scene(grays[m], options.scene_long_edge, outline);
    Limits limits;
    limits.max_width = std::max(limits.max_width, scene.cols);
    limits.max_height = std::max(limits.max_height, scene.rows);
    DesktopDetector detector(index.index(), limits);
    DetectionList found;
    if (Status s = detector.detect(scene, found); !s)
      return Status{s.code(), models[m].name + ": look-alike check: " + s.message()};
    out.models[m].scene_size = std::max(outline[1].x - outline[0].x, outline[3].y - outline[0].y);
    for (const Detection& d : found) {
      if (d.model_id < 0) continue;
      const auto id = static_cast<std::uint32_t>(d.model_id);
      if (id == m) {
        out.models[m].found_in_scene = true;
      } else if (std::find(others[m].begin(), others[m].end(), id) == others[m].end()) {
        others[m].push_back(id);
      }
    }
    std::sort(others[m].begin(), others[m].end());
    return Status::ok();
  });
  if (!checked) return checked;
  for (std::size_t m = 0; m < models.size(); ++m) {
    for (std::uint32_t id : others[m])
      out.look_alikes.push_back({static_cast<std::uint32_t>(m), id});
  }
  return Status::ok();
}

cv::Mat draw_model(const cv::Mat& gray, const BuiltModel& model, int max_keygraphs) {
  cv::Mat picture;
  cv::cvtColor(gray, picture, cv::COLOR_GRAY2BGR);
  // Faded, so that the drawing stands out.
  picture = picture * 0.6 + cv::Scalar(90, 90, 90);
  const std::size_t n = model.keypoints.size();
  // How many octaves of views saw each keypoint (0..255 codes, 8 per octave).
  auto span = [&](std::uint32_t k) {
    if (model.keypoint_views.size() != n) return 0;
    return model.keypoint_views[k][1] - model.keypoint_views[k][0];
  };
  // Undirected neighbours over the model arcs.
  std::vector<std::vector<std::uint32_t>> next(n);
  for (const ModelArc& a : model.arcs) {
    next[a.from].push_back(a.to);
    next[a.to].push_back(a.from);
  }
  for (auto& v : next) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
  // 3-circuits a < b < c, ranked by the smallest view span of their
  // keypoints, then by area (a larger keygraph is more stable).
  struct Triangle {
    std::uint32_t v[3];
    int span;
    float area;
  };
  std::vector<Triangle> triangles;
  for (std::uint32_t a = 0; a < n; ++a) {
    for (std::uint32_t b : next[a]) {
      if (b <= a) continue;
      for (std::uint32_t c : next[b]) {
        if (c <= b || !std::binary_search(next[a].begin(), next[a].end(), c)) continue;
        const Point2f pa = model.keypoints[a], pb = model.keypoints[b], pc = model.keypoints[c];
        const float area =
            0.5f * std::fabs((pb.x - pa.x) * (pc.y - pa.y) - (pc.x - pa.x) * (pb.y - pa.y));
        triangles.push_back({{a, b, c}, std::min({span(a), span(b), span(c)}), area});
      }
    }
  }
  const std::size_t shown = std::min(triangles.size(), static_cast<std::size_t>(max_keygraphs));
  std::partial_sort(triangles.begin(), triangles.begin() + static_cast<std::ptrdiff_t>(shown),
                    triangles.end(), [](const Triangle& x, const Triangle& y) {
                      return x.span != y.span ? x.span > y.span : x.area > y.area;
                    });
  const double thickness = std::max(2.0, std::max(gray.cols, gray.rows) / 200.0);
  for (std::size_t i = 0; i < shown; ++i) {
    const Triangle& t = triangles[i];
    cv::Point corners[3];
    for (int j = 0; j < 3; ++j)
      corners[j] = cv::Point(static_cast<int>(std::lround(model.keypoints[t.v[j]].x)),
                             static_cast<int>(std::lround(model.keypoints[t.v[j]].y)));
    // Strongest in red, the rest shading to orange.
    const double f = shown > 1 ? static_cast<double>(i) / static_cast<double>(shown - 1) : 0.0;
    const cv::Scalar colour(0, 60 + 140 * f, 255);
    cv::polylines(picture, std::vector<cv::Point>(corners, corners + 3), true, colour,
                  static_cast<int>(thickness), cv::LINE_AA);
  }
  // Keypoints as dots, with a thin circle of their detector scale.
  const int dot = std::max(2, static_cast<int>(thickness) + 1);
  for (std::size_t k = 0; k < n; ++k) {
    const cv::Point at(static_cast<int>(std::lround(model.keypoints[k].x)),
                       static_cast<int>(std::lround(model.keypoints[k].y)));
    const float sigma = k < model.keypoint_scales.size() ? model.keypoint_scales[k] : 0.f;
    if (sigma > static_cast<float>(dot))
      cv::circle(picture, at, static_cast<int>(std::lround(sigma)), cv::Scalar(230, 200, 150), 1,
                 cv::LINE_AA);
    cv::circle(picture, at, dot, cv::Scalar(255, 90, 0), cv::FILLED, cv::LINE_AA);
  }
  return picture;
}

}  // namespace kg
