#include "core/selection/triangle_check.h"

#include <algorithm>
#include <cstddef>

#include "core/keygraphs/keygraph.h"
#include "core/selection/triangle_patch.h"

namespace kg {

namespace {

// Marks a correspondence to drop between the measuring pass and the
// compaction: below any correlation (they lie in [-1, 1]); those dropped
// are gone before anyone reads it.
constexpr float kDropped = -2.f;
// Correspondences per task on the workers: a few hundred microseconds of
// patches, more than a wake-up of the workers costs.
constexpr std::size_t kChunk = 64;

}  // namespace

int check_triangle_patches(const ModelIndex& index, const Params& params, ImageView blurred,
                           const Point2f* scene_points, WorkVector<KeygraphMatch>& matches,
                           WorkerPool* workers) {
  const float threshold = params.ransac.min_triangle_correlation;
  if (!(threshold > 0.f) || vertex_count(params.graph.structure) < 3) return 0;
  const Point2f* model_points = index.keypoints();
  // Each correspondence is measured on its own (any thread), then those
  // marked are dropped in order (the caller's thread).
  const auto measure = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      KeygraphMatch& m = matches[i];
      const Point2f model[3] = {model_points[m.model_vertices[0]],
                                model_points[m.model_vertices[1]],
                                model_points[m.model_vertices[2]]};
      const Point2f scene[3] = {scene_points[static_cast<std::size_t>(m.scene_vertices[0])],
                                scene_points[static_cast<std::size_t>(m.scene_vertices[1])],
                                scene_points[static_cast<std::size_t>(m.scene_vertices[2])]};
      const TrianglePatch patch =
          triangle_patch_correlation(index.appearance(m.model_id), blurred, model, scene);
      if (patch.measured)
        m.patch_correlation = patch.correlation < threshold ? kDropped : patch.correlation;
    }
  };
  const std::size_t n = matches.size();
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  if (workers == nullptr || workers->threads() <= 1 || chunks <= 1) {
    measure(0, n);
  } else {
    auto chunk = [&](int c, int) {
      const std::size_t begin = static_cast<std::size_t>(c) * kChunk;
      measure(begin, std::min(n, begin + kChunk));
    };
    workers->run(chunks, chunk);
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (matches[i].patch_correlation == kDropped) continue;
    matches[kept++] = matches[i];
  }
  const int dropped = static_cast<int>(n - kept);
  matches.resize(kept);
  return dropped;
}

}  // namespace kg
