#include "build/model_builder.h"

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

#include "build/image_io.h"
#include "build/keypoints.h"
#include "build/model_views.h"
#include "build/sift_descriptors.h"
#include "core/arc_attributes.h"
#include "core/arc_descriptor.h"
#include "core/blur.h"
#include "core/crc32.h"
#include "core/descriptor_encoding.h"
#include "core/index_format.h"
#include "core/kdtree.h"
#include "core/keygraph.h"
#include "core/plane.h"
#include "core/sampling.h"
#include "platform/files/output_file.h"

namespace kg {

namespace {

template <class T>
constexpr DescriptorEncoding encoding_of() {
  if constexpr (std::is_same_v<T, std::int16_t>) {
    return DescriptorEncoding::kInt16;
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    return DescriptorEncoding::kInt8;
  } else {
    return DescriptorEncoding::kFloat32;
  }
}

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

namespace {

// The search tree over `descriptors` in the domain of T: quantised (int16,
// int8) or as computed (float), the arcs permuted into tree order.
template <class T>
void encode_tree(const std::vector<ArcSearchPoint>& search_points, double attribute_weight,
                 std::vector<ModelArc>& arcs, std::vector<std::uint8_t>& points_bytes,
                 std::vector<std::uint8_t>& node_bytes, std::vector<std::uint8_t>& bound_bytes) {
  using Point = KdPoint<T, kSearchDims>;
  std::vector<Point> source(search_points.size());
  for (std::size_t i = 0; i < search_points.size(); ++i) {
    if constexpr (std::is_same_v<T, float>) {
      source[i] = search_points[i];
    } else {
      source[i] = encode_point<T>(search_points[i]);
    }
  }
  std::vector<Point> points;
  std::vector<std::uint32_t> ids;
  std::vector<typename KdTraits<T>::Node> nodes;
  build_kdtree<T, kSearchDims>(source.data(), static_cast<std::uint32_t>(source.size()), points,
                               ids, nodes, attribute_weight);
  std::vector<ModelArc> ordered(arcs.size());
  for (std::size_t slot = 0; slot < ids.size(); ++slot) ordered[slot] = arcs[ids[slot]];
  arcs.swap(ordered);
  points_bytes.resize(points.size() * sizeof(Point));
  if (!points.empty()) std::memcpy(points_bytes.data(), points.data(), points_bytes.size());
  std::vector<Point> bounds;
  kdtree_leaf_bounds<T, kSearchDims>(points.data(), static_cast<std::uint32_t>(points.size()),
                                     bounds);
  bound_bytes.resize(bounds.size() * sizeof(Point));
  std::memcpy(bound_bytes.data(), bounds.data(), bound_bytes.size());
  // Nodes field by field: no padding bytes of the struct reach the file.
  node_bytes.assign(nodes.size() * format::tree_node_size(encoding_of<T>()), 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    std::uint8_t* p = node_bytes.data() + i * format::tree_node_size(encoding_of<T>());
    if constexpr (std::is_same_v<T, float>) {
      format::store<float>(p, nodes[i].split);
      format::store<std::uint32_t>(p + 4, nodes[i].dim);
    } else {
      format::store<std::int16_t>(p, nodes[i].split);
      format::store<std::uint16_t>(p + 2, nodes[i].dim);
    }
  }
}

}  // namespace

namespace {

// Sections 12-14 of `quality` (empty without one), checked against the
// models as the reader will check them.
Status encode_quality(const std::vector<BuiltModel>& models, const QualityReport* quality,
                      std::vector<std::uint8_t>& model_bytes, std::vector<std::uint8_t>& view_bytes,
                      std::vector<std::uint8_t>& pair_bytes) {
  using namespace format;
  model_bytes.clear();
  view_bytes.clear();
  pair_bytes.clear();
  if (quality == nullptr) return Status::ok();
  const auto invalid = [](const std::string& what) {
    return Status{StatusCode::kInvalidArgument, "quality report: " + what};
  };
  if (quality->models.size() != models.size()) return invalid("one record per model expected");
  std::uint32_t next_view = 0;
  model_bytes.assign(models.size() * kModelQualitySize, 0);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const ModelQuality& q = quality->models[m];
    if (q.view_begin != next_view || q.view_count > quality->views.size() - next_view)
      return invalid("view ranges not consecutive");
    if (q.shared_arcs > models[m].arcs.size()) return invalid("more shared arcs than arcs");
    next_view += q.view_count;
    std::uint8_t* r = model_bytes.data() + m * kModelQualitySize;
    store<std::uint32_t>(r + kMqViewBegin, q.view_begin);
    store<std::uint32_t>(r + kMqViewCount, q.view_count);
    store<std::uint32_t>(r + kMqSharedArcs, q.shared_arcs);
    store<float>(r + kMqSmallestSize, q.smallest_size);
    store<float>(r + kMqSceneSize, q.scene_size);
    store<std::uint32_t>(r + kMqFlags, q.found_in_scene ? kQualityFoundInScene : 0u);
  }
  if (next_view != quality->views.size()) return invalid("views not covered by the models");
  view_bytes.assign(quality->views.size() * kViewQualitySize, 0);
  for (std::size_t v = 0; v < quality->views.size(); ++v) {
    const ViewQuality& q = quality->views[v];
    std::uint8_t* r = view_bytes.data() + v * kViewQualitySize;
    store<float>(r + kVqScale, q.scale);
    store<float>(r + kVqTilt, q.tilt);
    store<float>(r + kVqLongitude, q.longitude);
    store<std::uint32_t>(r + kVqKeypoints, q.keypoints);
    store<std::uint32_t>(r + kVqArcs, q.arcs);
    store<std::uint32_t>(r + kVqKeygraphs, q.keygraphs);
  }
  pair_bytes.assign(quality->look_alikes.size() * kLookAlikeSize, 0);
  for (std::size_t i = 0; i < quality->look_alikes.size(); ++i) {
    const LookAlike& p = quality->look_alikes[i];
    if (p.shown >= models.size() || p.detected >= models.size() || p.shown == p.detected)
      return invalid("look-alike of an unknown model or of itself");
    if (i > 0) {
      const LookAlike& prev = quality->look_alikes[i - 1];
      if (prev.shown > p.shown || (prev.shown == p.shown && prev.detected >= p.detected))
        return invalid("look-alikes not sorted or repeated");
    }
    store<std::uint32_t>(pair_bytes.data() + i * kLookAlikeSize, p.shown);
    store<std::uint32_t>(pair_bytes.data() + i * kLookAlikeSize + 4, p.detected);
  }
  return Status::ok();
}

// Sections 15-16: every model's appearance when the parameters ask for
// them (empty when views.appearance_size is 0), checked as the reader will
// check them.
Status encode_appearances(const std::vector<BuiltModel>& models, const Params& params,
                          std::vector<std::uint8_t>& record_bytes,
                          std::vector<std::uint8_t>& pixel_bytes) {
  using namespace format;
  record_bytes.clear();
  pixel_bytes.clear();
  const int size = params.views.appearance_size;
  if (size == 0) return Status::ok();
  record_bytes.assign(models.size() * kAppearanceSize, 0);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    const cv::Mat& a = model.appearance;
    const int long_edge = std::max(model.width, model.height);
    const int want = std::min(size, long_edge);
    if (a.empty() || a.type() != CV_8UC1 || std::max(a.cols, a.rows) != want ||
        !(model.appearance_scale > 0.f && model.appearance_scale <= 1.f) ||
        (model.appearance_scale < 1.f) != (long_edge > size))
      return {StatusCode::kInvalidArgument,
              model.name + ": no appearance of " + std::to_string(want) +
                  " px on its long edge (build the model with the parameters of the index: "
                  "views.appearance_size " +
                  std::to_string(size) + ")"};
    if (pixel_bytes.size() + a.total() > 0xFFFFFFFFu)
      return {StatusCode::kInvalidArgument, "more than 2^32 - 1 appearance pixels"};
    std::uint8_t* r = record_bytes.data() + m * kAppearanceSize;
    store<std::uint32_t>(r + kApWidth, static_cast<std::uint32_t>(a.cols));
    store<std::uint32_t>(r + kApHeight, static_cast<std::uint32_t>(a.rows));
    store<float>(r + kApScale, model.appearance_scale);
    store<std::uint32_t>(r + kApFirstPixel, static_cast<std::uint32_t>(pixel_bytes.size()));
    for (int y = 0; y < a.rows; ++y) {
      const std::uint8_t* row = a.ptr<std::uint8_t>(y);
      pixel_bytes.insert(pixel_bytes.end(), row, row + a.cols);
    }
  }
  return Status::ok();
}

}  // namespace

Status serialize_index(const std::vector<BuiltModel>& models, const Params& params,
                       std::vector<std::uint8_t>& bytes, const QualityReport* quality) {
  using namespace format;
  Status s = validate_params(params);
  if (!s) return s;
  if (models.empty()) return {StatusCode::kInvalidArgument, "no models to write"};
  std::vector<std::uint8_t> quality_bytes, view_quality_bytes, look_alike_bytes;
  s = encode_quality(models, quality, quality_bytes, view_quality_bytes, look_alike_bytes);
  if (!s) return s;
  std::vector<std::uint8_t> appearance_bytes, appearance_pixels;
  s = encode_appearances(models, params, appearance_bytes, appearance_pixels);
  if (!s) return s;

  // Gather global arrays.
  std::vector<std::uint8_t> records(models.size() * kModelRecordSize, 0);
  std::string strings;
  std::vector<Point2f> keypoints;
  std::vector<float> keypoint_scales;
  std::vector<std::uint8_t> keypoint_views;
  std::vector<ModelArc> arcs;
  std::vector<ArcDescriptor> descriptors;
  std::vector<std::uint8_t> vertex_descriptors;
  const bool with_vertex = params.descriptor.vertex_descriptor != VertexDescriptor::kNone;
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    if (model.name.empty()) return {StatusCode::kInvalidArgument, "model with an empty name"};
    if (with_vertex && model.vertex_descriptors.size() !=
                           model.keypoints.size() * static_cast<std::size_t>(kVertexDescriptorSize))
      return {StatusCode::kInvalidArgument,
              model.name +
                  ": no vertex descriptors for every keypoint (build the model with "
                  "the parameters of the index)"};
    if (model.keypoint_scales.size() != model.keypoints.size())
      return {StatusCode::kInvalidArgument, model.name + ": one scale per keypoint expected"};
    if (!model.keypoint_views.empty() && model.keypoint_views.size() != model.keypoints.size())
      return {StatusCode::kInvalidArgument, model.name + ": one view range per keypoint expected"};
    if (model.descriptors.size() != model.arcs.size())
      return {StatusCode::kInvalidArgument, model.name + ": one descriptor per arc expected"};
    std::uint8_t* r = records.data() + m * kModelRecordSize;
    const auto kp_begin = static_cast<std::uint32_t>(keypoints.size());
    store<std::uint32_t>(r + kModNameOffset, static_cast<std::uint32_t>(strings.size()));
    store<std::uint32_t>(r + kModNameLength, static_cast<std::uint32_t>(model.name.size()));
    store<float>(r + kModWidth, static_cast<float>(model.width));
    store<float>(r + kModHeight, static_cast<float>(model.height));
    store<std::uint32_t>(r + kModKeypointBegin, kp_begin);
    store<std::uint32_t>(r + kModKeypointCount, static_cast<std::uint32_t>(model.keypoints.size()));
    store<std::uint32_t>(r + kModArcCount, static_cast<std::uint32_t>(model.arcs.size()));
    store<std::uint64_t>(r + kModKeygraphCount, model.keygraphs);
    // Outline: the image rectangle through the pixel centres of its corners,
    // clockwise on screen.
    const float w = static_cast<float>(model.width - 1), h = static_cast<float>(model.height - 1);
    const float outline[8] = {0.f, 0.f, w, 0.f, w, h, 0.f, h};
    for (int c = 0; c < 8; ++c) store<float>(r + kModOutline + 4 * c, outline[c]);
    strings += model.name;
    keypoints.insert(keypoints.end(), model.keypoints.begin(), model.keypoints.end());
    keypoint_scales.insert(keypoint_scales.end(), model.keypoint_scales.begin(),
                           model.keypoint_scales.end());
    for (std::size_t k = 0; k < model.keypoints.size(); ++k) {
      const bool known = !model.keypoint_views.empty();
      keypoint_views.push_back(known ? model.keypoint_views[k][0] : 0);
      keypoint_views.push_back(known ? model.keypoint_views[k][1] : 255);
    }
    for (const ModelArc& a : model.arcs) arcs.push_back({a.from + kp_begin, a.to + kp_begin});
    descriptors.insert(descriptors.end(), model.descriptors.begin(), model.descriptors.end());
    if (with_vertex)
      vertex_descriptors.insert(vertex_descriptors.end(), model.vertex_descriptors.begin(),
                                model.vertex_descriptors.end());
  }
  if (arcs.size() > 0xFFFFFFFFu || keypoints.size() > 0xFFFFFFFFu)
    return {StatusCode::kInvalidArgument, "more than 2^32 - 1 arcs or keypoints"};
  // Tree points: each descriptor with its arc's scale attributes.
  std::vector<ArcSearchPoint> search_points(arcs.size());
  std::vector<std::array<float, 2>> attributes(arcs.size());
  {
    std::size_t i = 0;
    for (const BuiltModel& model : models) {
      for (std::size_t a = 0; a < model.arcs.size(); ++a, ++i) {
        if (model.arc_attributes.size() == model.arcs.size()) {
          attributes[i] = model.arc_attributes[a];
        } else {  // zero when a scale is unknown
          arc_attributes(keypoints[arcs[i].from], keypoints[arcs[i].to],
                         keypoint_scales[arcs[i].from], keypoint_scales[arcs[i].to],
                         attributes[i].data());
        }
      }
    }
  }
  for (std::size_t i = 0; i < arcs.size(); ++i)
    search_points[i] = search_point(descriptors[i], attributes[i].data());
  // Attributes are split as often as descriptor components when their box
  // is as wide, in the stored domain, as the similarity radius; never when
  // the box is off.
  const double box = attribute_box(params.graph);  // grid steps, in every encoding
  const double radius = static_cast<double>(params.descriptor.similarity_threshold) *
                        encoding_scale(params.descriptor.encoding);
  const double attribute_weight = box > 0.0 ? 0.5 * radius / box : 0.0;
  // Search tree in the parameters' encoding; arcs permuted into tree order.
  const DescriptorEncoding encoding = params.descriptor.encoding;
  std::vector<std::uint8_t> tree_points, tree_nodes, leaf_bounds;
  switch (encoding) {
    case DescriptorEncoding::kFloat32:
      encode_tree<float>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                         leaf_bounds);
      break;
    case DescriptorEncoding::kInt16:
      encode_tree<std::int16_t>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                                leaf_bounds);
      break;
    case DescriptorEncoding::kInt8:
      encode_tree<std::int8_t>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                               leaf_bounds);
      break;
  }
  const auto encoding_id = static_cast<std::uint32_t>(encoding);

  struct Payload {
    std::uint32_t id;
    std::uint32_t encoding;
    const void* data;
    std::size_t size;
    std::uint32_t count;
  };
  const auto arc_count = static_cast<std::uint32_t>(arcs.size());
  // Arcs as two aligned arrays: sources, and targets as int16 offsets (a
  // model's keypoints are at most kMaxModelKeypoints apart in id).
  std::vector<std::uint32_t> arc_from(arcs.size());
  std::vector<std::int16_t> arc_to_offset(arcs.size());
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    const std::int64_t offset =
        static_cast<std::int64_t>(arcs[i].to) - static_cast<std::int64_t>(arcs[i].from);
    if (offset < -32768 || offset > 32767)
      return {StatusCode::kInvalidArgument, "a model has more than 32768 keypoints"};
    arc_from[i] = arcs[i].from;
    arc_to_offset[i] = static_cast<std::int16_t>(offset);
  }
  const Payload payloads[kLastSectionId] = {
      {kSectionModels, 0, records.data(), records.size(),
       static_cast<std::uint32_t>(models.size())},
      {kSectionStrings, 0, strings.data(), strings.size(),
       static_cast<std::uint32_t>(strings.size())},
      {kSectionKeypoints, 0, keypoints.data(), keypoints.size() * sizeof(Point2f),
       static_cast<std::uint32_t>(keypoints.size())},
      {kSectionTreeArcs, 0, arc_from.data(), arc_from.size() * sizeof(std::uint32_t), arc_count},
      {kSectionDescriptors, encoding_id, tree_points.data(), tree_points.size(), arc_count},
      {kSectionTreeNodes, encoding_id, tree_nodes.data(), tree_nodes.size(),
       static_cast<std::uint32_t>(tree_nodes.size() / tree_node_size(encoding))},
      {kSectionVertexDescriptors, 0, vertex_descriptors.data(), vertex_descriptors.size(),
       static_cast<std::uint32_t>(vertex_descriptors.size() / kVertexDescriptorSize)},
      {kSectionKeypointScales, 0, keypoint_scales.data(), keypoint_scales.size() * sizeof(float),
       static_cast<std::uint32_t>(keypoint_scales.size())},
      {kSectionTreeArcTargets, 0, arc_to_offset.data(), arc_to_offset.size() * sizeof(std::int16_t),
       arc_count},
      {kSectionLeafBounds, encoding_id, leaf_bounds.data(), leaf_bounds.size(),
       static_cast<std::uint32_t>(leaf_bounds.size() / encoded_point_size(encoding))},
      {kSectionKeypointViews, 0, keypoint_views.data(), keypoint_views.size(),
       static_cast<std::uint32_t>(keypoint_views.size() / 2)},
      {kSectionModelQuality, 0, quality_bytes.data(), quality_bytes.size(),
       static_cast<std::uint32_t>(quality_bytes.size() / kModelQualitySize)},
      {kSectionViewQuality, 0, view_quality_bytes.data(), view_quality_bytes.size(),
       static_cast<std::uint32_t>(view_quality_bytes.size() / kViewQualitySize)},
      {kSectionLookAlikes, 0, look_alike_bytes.data(), look_alike_bytes.size(),
       static_cast<std::uint32_t>(look_alike_bytes.size() / kLookAlikeSize)},
      {kSectionAppearances, 0, appearance_bytes.data(), appearance_bytes.size(),
       static_cast<std::uint32_t>(appearance_bytes.size() / kAppearanceSize)},
      {kSectionAppearancePixels, 0, appearance_pixels.data(), appearance_pixels.size(),
       static_cast<std::uint32_t>(appearance_pixels.size())},
  };
  const std::size_t params_offset = kHeaderSize;
  const std::size_t table_offset = params_offset + kParamsSize;
  const std::size_t table_end = table_offset + kLastSectionId * kSectionEntrySize;
  std::size_t offset = align_up(table_end);
  std::size_t offsets[kLastSectionId];
  for (std::uint32_t i = 0; i < kLastSectionId; ++i) {
    offsets[i] = offset;
    offset = align_up(offset + payloads[i].size);
  }
  bytes.assign(offset, 0);
  std::uint8_t* d = bytes.data();
  std::copy(std::begin(kMagic), std::end(kMagic), d + kOffMagic);
  store<std::uint16_t>(d + kOffMajor, kVersionMajor);
  store<std::uint16_t>(d + kOffMinor, kVersionMinor);
  store<std::uint32_t>(d + kOffHeaderSize, static_cast<std::uint32_t>(kHeaderSize));
  store<std::uint64_t>(d + kOffFileSize, static_cast<std::uint64_t>(bytes.size()));
  store<std::uint32_t>(d + kOffParamsOffset, static_cast<std::uint32_t>(params_offset));
  store<std::uint32_t>(d + kOffParamsSize, static_cast<std::uint32_t>(kParamsSize));
  store<std::uint32_t>(d + kOffTableOffset, static_cast<std::uint32_t>(table_offset));
  store<std::uint32_t>(d + kOffSectionCount, kLastSectionId);
  serialize_params(params, d + params_offset);
  for (std::uint32_t i = 0; i < kLastSectionId; ++i) {
    const Payload& p = payloads[i];
    if (p.size > 0) std::memcpy(d + offsets[i], p.data, p.size);
    std::uint8_t* e = d + table_offset + i * kSectionEntrySize;
    store<std::uint32_t>(e + kEntId, p.id);
    store<std::uint32_t>(e + kEntEncoding, p.encoding);
    store<std::uint64_t>(e + kEntOffset, offsets[i]);
    store<std::uint64_t>(e + kEntSize, p.size);
    store<std::uint32_t>(e + kEntCount, p.count);
    store<std::uint32_t>(e + kEntCrc, crc32(d + offsets[i], p.size));
  }
  store<std::uint32_t>(d + kOffHeaderCrc, crc32(d, table_end));
  return Status::ok();
}

Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   const std::string& path, const QualityReport* quality) {
  platform::OutputFile out;
  if (Status s = out.create(path); !s) return s;
  return write_index(models, params, out, quality);
}

Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   platform::OutputFile& out, const QualityReport* quality) {
  std::vector<std::uint8_t> bytes;
  Status s = serialize_index(models, params, bytes, quality);
  if (s) s = out.write(bytes.data(), bytes.size());
  if (s) s = out.commit();
  if (!s) out.discard();
  return s;
}

}  // namespace kg
