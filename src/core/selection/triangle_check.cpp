#include "core/selection/triangle_check.h"

#include <cstddef>

#include "core/keygraphs/keygraph.h"
#include "core/selection/triangle_patch.h"

namespace kg {

int check_triangle_patches(const ModelIndex& index, const Params& params, ImageView blurred,
                           const Point2f* scene_points, WorkVector<KeygraphMatch>& matches) {
  const float threshold = params.ransac.min_triangle_correlation;
  if (!(threshold > 0.f) || vertex_count(params.graph.structure) < 3) return 0;
  const Point2f* model_points = index.keypoints();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    KeygraphMatch& m = matches[i];
    const Point2f model[3] = {model_points[m.model_vertices[0]], model_points[m.model_vertices[1]],
                              model_points[m.model_vertices[2]]};
    const Point2f scene[3] = {scene_points[static_cast<std::size_t>(m.scene_vertices[0])],
                              scene_points[static_cast<std::size_t>(m.scene_vertices[1])],
                              scene_points[static_cast<std::size_t>(m.scene_vertices[2])]};
    const TrianglePatch patch =
        triangle_patch_correlation(index.appearance(m.model_id), blurred, model, scene);
    if (patch.measured) {
      m.patch_correlation = patch.correlation;
      if (patch.correlation < threshold) continue;
    }
    matches[kept++] = m;
  }
  const int dropped = static_cast<int>(matches.size() - kept);
  matches.resize(kept);
  return dropped;
}

}  // namespace kg
