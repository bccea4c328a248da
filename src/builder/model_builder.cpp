#include "builder/model_builder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>
#include <type_traits>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "builder/image_io.h"
#include "builder/keypoints.h"
#include "builder/model_views.h"
#include "builder/sift_descriptors.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/image/blur.h"
#include "core/image/plane.h"
#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "core/index/kdtree.h"
#include "core/keygraphs/keygraph.h"
#include "core/sampling/sampling.h"
#include "platform/files/output_file.h"

namespace kg {

namespace {

// Model keypoints without views (the paper's model): the detector on the
// image at several scales, mapped back to model pixels, near-duplicates
// merged (strongest kept).
void model_keypoints(const cv::Mat& gray, const KeypointParams& params,
                     std::vector<Keypoint>& out) {
  KeypointExtractor extractor;
  std::vector<Keypoint> all, level;
  cv::Mat scaled;
  for (int s = 0; s < params.model_scales; ++s) {
    const double scale = std::pow(std::sqrt(0.5), s);
    const int w = static_cast<int>(std::lround(gray.cols * scale));
    const int h = static_cast<int>(std::lround(gray.rows * scale));
    if (w < 32 || h < 32) break;
    if (s == 0) {
      scaled = gray;
    } else {
      cv::resize(gray, scaled, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    }
    extractor.extract(scaled, params, 1 << 20, level);
    const double sx = static_cast<double>(gray.cols) / w, sy = static_cast<double>(gray.rows) / h;
    for (Keypoint k : level) {
      // Pixel centres: x_model + 0.5 = (x_scaled + 0.5) * sx.
      k.x = static_cast<float>((k.x + 0.5) * sx - 0.5);
      k.y = static_cast<float>((k.y + 0.5) * sy - 0.5);
      k.scale = static_cast<float>(k.scale * sx);
      all.push_back(k);
    }
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const Keypoint& a, const Keypoint& b) { return a.response > b.response; });
  std::vector<int> kept;
  SeparatedSampler sampler;
  sampler.sample(all.data(), static_cast<int>(all.size()),
                 std::max(params.model_merge_distance, 1e-3f), nullptr, kept);
  std::sort(kept.begin(), kept.end());  // strongest first (all is sorted)
  if (static_cast<int>(kept.size()) > params.max_model_keypoints)
    kept.resize(static_cast<std::size_t>(params.max_model_keypoints));
  out.clear();
  for (int i : kept) out.push_back(all[i]);
}

// Arc descriptors as the frames compute them: fixed point for the integer
// encodings (stored as q / scale, which quantise() turns back into q
// exactly), float otherwise.
class ArcDescriber {
 public:
  explicit ArcDescriber(const DescriptorParams& params)
      : params_(params),
        fixed_(uses_fixed_point(params)),
        scale_(encoding_scale(params.encoding)) {}
  void set_image(const cv::Mat& gray) {
    gaussian_blur(view_of(gray), params_.blur_sigma, blurred_, scratch_);
  }
  bool describe(Point2f from, Point2f to, ArcDescriptor& d) {
    const ImageView bv = view_of(blurred_);
    if (!fixed_) return arc_descriptor(bv, from, to, params_, profile_, d);
    std::int32_t q[kDescriptorSize];
    if (!arc_descriptor_fixed(bv, from, to, params_, scale_, sums_, q)) return false;
    for (int i = 0; i < kDescriptorSize; ++i)
      d[i] = static_cast<float>(q[i]) / static_cast<float>(scale_);
    return true;
  }

 private:
  const DescriptorParams& params_;
  bool fixed_;
  std::int32_t scale_;
  Plane<std::uint8_t> blurred_;
  Plane<float> scratch_;
  std::vector<float> profile_;
  std::vector<std::int32_t> sums_;
};

// In double: the products of floats are exact there, so the result does not
// depend on whether the compiler fuses the multiply-add.
double squared_length(Point2f a, Point2f b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  return dx * dx + dy * dy;
}

// Whether local keypoints a and b, two different model keypoints, are in
// arc range of each other (GraphParams: Chebyshev and relative length).
bool arc_partners(const std::vector<Keypoint>& points, const std::vector<std::uint32_t>& ids,
                  std::size_t a, std::size_t b, const GraphParams& graph) {
  if (a == b || ids[a] == ids[b]) return false;
  return is_model_arc(Point2f{points[a].x, points[a].y}, Point2f{points[b].x, points[b].y},
                      points[a].scale, points[b].scale, graph);
}

// Per local keypoint, the squared distance to its `rank`-th nearest arc
// partner (another model keypoint within the arc range), or infinity when it
// has no more partners than that: arcs no longer than either end's are the
// near-neighbour arcs graph.max_neighbour_rank keeps. Partners whose arc
// cannot be described (near the view's border) are counted too, so a
// keypoint may keep fewer than `rank` arcs.
std::vector<double> neighbour_radii(const std::vector<Keypoint>& points,
                                    const std::vector<std::uint32_t>& ids,
                                    const GraphParams& graph) {
  const std::size_t n = points.size();
  std::vector<double> radii(n, std::numeric_limits<double>::infinity());
  const auto rank = static_cast<std::size_t>(std::max(0, graph.max_neighbour_rank));
  if (rank == 0) return radii;
  std::vector<double> d2;
  for (std::size_t a = 0; a < n; ++a) {
    d2.clear();
    const Point2f pa{points[a].x, points[a].y};
    for (std::size_t b = 0; b < n; ++b)
      if (arc_partners(points, ids, a, b, graph))
        d2.push_back(squared_length(pa, {points[b].x, points[b].y}));
    if (d2.size() <= rank) continue;
    std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(rank - 1), d2.end());
    radii[a] = d2[rank - 1];
  }
  return radii;
}

// Arcs of one keypoint set in one image: every pair within the Chebyshev
// range (and, with graph.max_neighbour_rank, among either end's nearest),
// described on that image. ids map local keypoints to model ids.
// `described` (optional) gets, per local keypoint a, the local targets of
// the arcs described from it (duplicates of other views' arcs included):
// offsets (n + 1) and targets, as count_model_keygraphs() reads them.
struct LocalArcs {
  std::vector<std::uint32_t> offsets, to;
};
void add_arcs(const std::vector<Keypoint>& points, const std::vector<std::uint32_t>& ids,
              const Params& params, ArcDescriber& describer, BuiltModel& out,
              std::vector<std::vector<std::uint32_t>>& arcs_by_pair_from,
              LocalArcs* described = nullptr) {
  const std::size_t n = points.size();
  if (described != nullptr) {
    described->offsets.assign(n + 1, 0);
    described->to.clear();
  }
  const std::vector<double> radii = neighbour_radii(points, ids, params.graph);
  for (std::size_t a = 0; a < n; ++a) {
    if (described != nullptr)
      described->offsets[a] = static_cast<std::uint32_t>(described->to.size());
    const Point2f pa{points[a].x, points[a].y};
    for (std::size_t b = 0; b < n; ++b) {
      if (!arc_partners(points, ids, a, b, params.graph)) continue;
      const Point2f pb{points[b].x, points[b].y};
      const double length2 = squared_length(pa, pb);
      if (length2 > radii[a] && length2 > radii[b]) continue;
      ArcDescriptor d;
      if (!describer.describe(pa, pb, d)) continue;
      if (described != nullptr) described->to.push_back(static_cast<std::uint32_t>(b));
      float attributes[kArcAttributes];
      arc_attributes(pa, pb, points[a].scale, points[b].scale, attributes);
      // Stored once when another view already described it alike.
      bool duplicate = false;
      const bool dedupe = params.views.dedupe_distance >= 0.f;
      const float limit2 = params.views.dedupe_distance * params.views.dedupe_distance;
      for (std::uint32_t other : arcs_by_pair_from[ids[a]]) {
        if (!dedupe) break;
        if (out.arcs[other].to != ids[b]) continue;
        float d2 = 0.f;
        for (int i = 0; i < kDescriptorSize; ++i) {
          const float e = d[i] - out.descriptors[other][i];
          d2 += e * e;
        }
        const auto& o = out.arc_attributes[other];
        if (d2 <= limit2 && std::fabs(o[0] - attributes[0]) <= 1.f &&
            std::fabs(o[1] - attributes[1]) <= 1.f) {
          duplicate = true;
          break;
        }
      }
      if (duplicate) continue;
      arcs_by_pair_from[ids[a]].push_back(static_cast<std::uint32_t>(out.arcs.size()));
      out.arcs.push_back({ids[a], ids[b]});
      out.descriptors.push_back(d);
      out.arc_attributes.push_back({attributes[0], attributes[1]});
    }
  }
  if (described != nullptr)
    described->offsets[n] = static_cast<std::uint32_t>(described->to.size());
}

// Model keypoints found so far, with a grid for merging those of later
// views that land within a view-dependent radius.
class ModelKeypointSet {
 public:
  // The model keypoint within `radius` model pixels of p, or a new one.
  std::uint32_t add(Point2f p, float sigma, float radius, std::uint8_t code, bool& added) {
    const int cx = cell(p.x), cy = cell(p.y);
    const int reach = static_cast<int>(std::ceil(radius / kCell));
    std::uint32_t best = kNone;
    float best_d2 = radius * radius;
    for (int y = cy - reach; y <= cy + reach; ++y) {
      for (int x = cx - reach; x <= cx + reach; ++x) {
        const auto it = cells_.find(key(x, y));
        if (it == cells_.end()) continue;
        for (std::uint32_t id : it->second) {
          const float dx = points_[id].x - p.x, dy = points_[id].y - p.y;
          const float d2 = dx * dx + dy * dy;
          if (d2 <= best_d2) best = id, best_d2 = d2;
        }
      }
    }
    added = best == kNone;
    if (!added) {
      views_[best][0] = std::min(views_[best][0], code);
      views_[best][1] = std::max(views_[best][1], code);
      return best;
    }
    const auto id = static_cast<std::uint32_t>(points_.size());
    points_.push_back(p);
    sigmas_.push_back(sigma);
    views_.push_back({code, code});
    cells_[key(cx, cy)].push_back(id);
    return id;
  }
  const std::vector<Point2f>& points() const { return points_; }
  const std::vector<float>& sigmas() const { return sigmas_; }
  const std::vector<std::array<std::uint8_t, 2>>& views() const { return views_; }

 private:
  static constexpr float kCell = 4.f;
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  int cell(float v) const { return static_cast<int>(std::floor(v / kCell)); }
  std::int64_t key(int x, int y) const {
    return (static_cast<std::int64_t>(y) << 32) ^ static_cast<std::uint32_t>(x);
  }
  std::vector<Point2f> points_;
  std::vector<float> sigmas_;
  std::vector<std::array<std::uint8_t, 2>> views_;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> cells_;
};

// The model through simulated views (ViewParams): per view, its keypoints
// mapped back to model pixels (merged with earlier views' within
// merge_distance view pixels), and its arcs described on the view with
// attributes in view pixels, between model keypoint ids.
Status build_views(const cv::Mat& gray, const Params& params, BuiltModel& out) {
  const std::vector<ModelView> views = model_views(gray.cols, gray.rows, params.views, 1);
  ModelKeypointSet set;
  KeypointExtractor extractor;
  ArcDescriber describer(params.descriptor);
  std::vector<std::vector<std::uint32_t>> arcs_by_from;
  std::vector<Keypoint> detected, kept;
  std::vector<std::uint32_t> ids;
  LocalArcs described;
  std::vector<Point2f> view_points;
  cv::Mat image, inside;
  for (const ModelView& view : views) {
    render_view(gray, view, image, inside);
    extractor.extract(image, params.keypoints, params.keypoints.max_model_keypoints, detected);
    const cv::Matx23d& a = view.to_view;
    const double det = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
    // Inverse map view -> model.
    const double i00 = a(1, 1) / det, i01 = -a(0, 1) / det, i10 = -a(1, 0) / det,
                 i11 = a(0, 0) / det;
    const float radius =
        params.views.merge_distance / static_cast<float>(std::sqrt(std::fabs(det)));
    // This view's scale code: -log2 of its area scale, eighths of an octave.
    const double code = std::round(-0.5 * std::log2(std::fabs(det)) * format::kViewCodesPerOctave);
    const auto view_code = static_cast<std::uint8_t>(std::clamp(code, 0.0, 255.0));
    kept.clear();
    ids.clear();
    for (const Keypoint& k : detected) {
      const int x = static_cast<int>(std::lround(k.x)), y = static_cast<int>(std::lround(k.y));
      if (x < 0 || y < 0 || x >= inside.cols || y >= inside.rows ||
          inside.at<std::uint8_t>(y, x) == 0)
        continue;
      const double vx = k.x - a(0, 2), vy = k.y - a(1, 2);
      const Point2f m{static_cast<float>(i00 * vx + i01 * vy),
                      static_cast<float>(i10 * vx + i11 * vy)};
      const float right = static_cast<float>(gray.cols) - 0.5f;
      const float bottom = static_cast<float>(gray.rows) - 0.5f;
      if (!(m.x >= -0.5f && m.y >= -0.5f && m.x <= right && m.y <= bottom)) continue;
      if (set.points().size() >= static_cast<std::size_t>(format::kMaxModelKeypoints) - 1) break;
      bool added = false;
      const std::uint32_t id = set.add(m, static_cast<float>(k.scale / std::sqrt(std::fabs(det))),
                                       radius, view_code, added);
      // One view keypoint per model keypoint in this view.
      if (std::find(ids.begin(), ids.end(), id) != ids.end()) continue;
      kept.push_back(k);
      ids.push_back(id);
    }
    arcs_by_from.resize(set.points().size());
    describer.set_image(image);
    const std::size_t arcs_before = out.arcs.size();
    add_arcs(kept, ids, params, describer, out, arcs_by_from, &described);
    // What a frame showing the model at this view's size could match.
    view_points.clear();
    for (const Keypoint& k : kept) view_points.push_back({k.x, k.y});
    ViewSummary summary;
    summary.scale = view.scale;
    summary.tilt = view.tilt;
    summary.longitude = view.longitude;
    summary.blur = view.blur;
    summary.glow = view.glow;
    summary.width = view.size.width;
    summary.height = view.size.height;
    summary.keypoints = static_cast<int>(kept.size());
    summary.arcs = static_cast<int>(out.arcs.size() - arcs_before);
    summary.view_arcs = static_cast<int>(described.to.size());
    summary.keygraphs =
        count_model_keygraphs(view_points.data(), static_cast<int>(view_points.size()),
                              described.offsets.data(), described.to.data(), params.graph);
    out.views.push_back(summary);
  }
  out.keypoints = set.points();
  out.keypoint_scales = set.sigmas();
  out.keypoint_views = set.views();
  return Status::ok();
}

}  // namespace

// A short edge that would round to nothing keeps one pixel.
void model_appearance(const cv::Mat& gray, int size, cv::Mat& out, float& scale) {
  const int long_edge = std::max(gray.cols, gray.rows);
  if (long_edge <= size) {
    out = gray.clone();
    scale = 1.f;
    return;
  }
  const double factor = static_cast<double>(size) / long_edge;
  const cv::Size at_factor(cvRound(gray.cols * factor), cvRound(gray.rows * factor));
  if (at_factor.width >= 1 && at_factor.height >= 1) {
    // dsize from the factors: the same factor along both axes.
    cv::resize(gray, out, cv::Size(), factor, factor, cv::INTER_AREA);
  } else {
    cv::resize(gray, out, cv::Size(std::max(1, at_factor.width), std::max(1, at_factor.height)), 0,
               0, cv::INTER_AREA);
  }
  scale = static_cast<float>(factor);
}

Status build_model(const cv::Mat& gray, const std::string& name, const Params& params,
                   BuiltModel& out) {
  Status s = format::validate_params(params);
  if (!s) return s;
  if (gray.empty() || gray.type() != CV_8UC1)
    return {StatusCode::kInvalidArgument, name + ": model image must be 8-bit gray"};
  out = BuiltModel{};
  out.name = name;
  out.width = gray.cols;
  out.height = gray.rows;

  if (params.views.min_size > 0.f) {
    if (s = build_views(gray, params, out); !s) return s;
    if (params.descriptor.vertex_descriptor == VertexDescriptor::kSift) {
      // On the model image, at each keypoint's scale in model pixels.
      std::vector<Keypoint> keypoints(out.keypoints.size());
      for (std::size_t i = 0; i < keypoints.size(); ++i)
        keypoints[i] = {out.keypoints[i].x, out.keypoints[i].y, out.keypoint_scales[i], 0.f};
      SiftDescriber sift;
      sift.describe(gray, keypoints.data(), static_cast<int>(keypoints.size()),
                    out.vertex_descriptors);
    }
  } else {
    std::vector<Keypoint> keypoints;
    model_keypoints(gray, params.keypoints, keypoints);
    // Sort by position so arcs and files do not depend on response ties.
    std::sort(keypoints.begin(), keypoints.end(), [](const Keypoint& a, const Keypoint& b) {
      return a.y < b.y || (a.y == b.y && a.x < b.x);
    });
    std::vector<std::uint32_t> ids;
    for (const Keypoint& k : keypoints) {
      ids.push_back(static_cast<std::uint32_t>(out.keypoints.size()));
      out.keypoints.push_back({k.x, k.y});
      out.keypoint_scales.push_back(k.scale);
      out.keypoint_views.push_back({0, 255});  // no views: every scale
    }
    if (params.descriptor.vertex_descriptor == VertexDescriptor::kSift) {
      SiftDescriber sift;
      sift.describe(gray, keypoints.data(), static_cast<int>(keypoints.size()),
                    out.vertex_descriptors);
    }
    ArcDescriber describer(params.descriptor);
    describer.set_image(gray);
    std::vector<std::vector<std::uint32_t>> arcs_by_from(keypoints.size());
    Params single = params;
    single.views.dedupe_distance = -1.f;  // one image: nothing to deduplicate
    add_arcs(keypoints, ids, single, describer, out, arcs_by_from);
    ViewSummary summary;
    summary.width = gray.cols;
    summary.height = gray.rows;
    summary.keypoints = static_cast<int>(keypoints.size());
    summary.arcs = static_cast<int>(out.arcs.size());
    summary.view_arcs = summary.arcs;
    out.views.push_back(summary);  // keygraphs: the model's, below
  }
  // Arcs sorted by (from, to): files do not depend on the views' order.
  {
    std::vector<std::size_t> order(out.arcs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return out.arcs[a].from < out.arcs[b].from ||
             (out.arcs[a].from == out.arcs[b].from && out.arcs[a].to < out.arcs[b].to);
    });
    BuiltModel sorted;
    for (std::size_t i : order) {
      sorted.arcs.push_back(out.arcs[i]);
      sorted.descriptors.push_back(out.descriptors[i]);
      sorted.arc_attributes.push_back(out.arc_attributes[i]);
    }
    out.arcs.swap(sorted.arcs);
    out.descriptors.swap(sorted.descriptors);
    out.arc_attributes.swap(sorted.arc_attributes);
  }
  const auto n = static_cast<std::uint32_t>(out.keypoints.size());
  std::vector<std::uint32_t> offsets(n + 1, 0), to;
  {
    std::size_t at = 0;
    for (std::uint32_t a = 0; a <= n; ++a) {
      while (at < out.arcs.size() && out.arcs[at].from < a) ++at;
      offsets[a] = static_cast<std::uint32_t>(at);
    }
  }
  // Distinct targets per source (views may describe one pair twice).
  std::vector<std::uint32_t> unique_offsets(n + 1, 0);
  for (std::uint32_t a = 0; a < n; ++a) {
    unique_offsets[a] = static_cast<std::uint32_t>(to.size());
    for (std::uint32_t i = offsets[a]; i < offsets[a + 1]; ++i) {
      if (i == offsets[a] || out.arcs[i].to != out.arcs[i - 1].to) to.push_back(out.arcs[i].to);
    }
  }
  unique_offsets[n] = static_cast<std::uint32_t>(to.size());
  // Keygraphs over arcs that have descriptors (the ones selection can find).
  out.keygraphs = count_model_keygraphs(out.keypoints.data(), static_cast<int>(n),
                                        unique_offsets.data(), to.data(), params.graph);
  if (params.views.min_size <= 0.f && !out.views.empty()) out.views[0].keygraphs = out.keygraphs;
  if (out.arcs.empty())
    return {StatusCode::kInvalidArgument, name + ": no model arcs (" + std::to_string(n) +
                                              " keypoints); image too small or flat"};
  if (params.views.appearance_size > 0)
    model_appearance(gray, params.views.appearance_size, out.appearance, out.appearance_scale);
  return Status::ok();
}

}  // namespace kg
