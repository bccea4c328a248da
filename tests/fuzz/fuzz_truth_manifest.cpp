// libFuzzer target for the ground-truth manifest of eval --truth
// (eval/truth_manifest.h, docs/EVAL.md): each input is a manifest's text,
// parsed line by line, and whole as read_truth_manifest() does (line
// length, nesting depth and duplicate keys bounded by builder/strict_json.h). What a line accepts
// is checked against the parser's promises -- four corners forming a simple quadrilateral, a
// homography with h33 = 1, at least one non-empty model name per instance -- and fed to the scoring
// geometry (order-free corner error, IoU in [0, 1], also against its own corners reversed).
//
// Seeds: tests/fuzz/seeds/truth_manifest/ (one line of each kind, and a
// converted real-set line).
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_truth_manifest
//   build/fuzz/tests/fuzz/fuzz_truth_manifest CORPUS_DIR tests/fuzz/seeds/truth_manifest \
//     -max_total_time=60
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "eval/quad_geometry.h"
#include "eval/truth_manifest.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void exercise(const kg::TruthScene& scene) {
  check(!scene.scene.empty());
  std::string error;
  (void)kg::check_truth_models(scene, {"a", "exit-left", "exit-right"}, error);
  for (const kg::TruthInstance& i : scene.instances) {
    check(!i.models.empty());
    for (const std::string& m : i.models) check(!m.empty());
    if (i.has_homography) {
      check(i.models.size() == 1 && i.homography[8] == 1.0);
      continue;
    }
    check(kg::is_simple_quad(i.corners));
    kg::Point2f reversed[4];
    for (int c = 0; c < 4; ++c) reversed[c] = i.corners[3 - c];
    check(kg::order_free_corner_error(i.corners, reversed) == 0.0);
    const double self = kg::quad_iou(i.corners, reversed);
    check(self >= 0.0 && self <= 1.0);
    // Away from float round-off (tiny or far-flung shapes), a shape covers itself.
    double extent = 0;
    for (const kg::Point2f& p : i.corners)
      extent = std::fmax(extent, std::fmax(std::fabs(p.x), std::fabs(p.y)));
    if (std::fabs(kg::signed_area(i.corners)) >= 1.0 && extent <= 1e4) check(self > 0.99);
    for (const kg::TruthInstance& j : scene.instances) {
      if (j.has_homography) continue;
      const double iou = kg::quad_iou(i.corners, j.corners);
      check(iou >= 0.0 && iou <= 1.0);
      check(kg::order_free_corner_error(i.corners, j.corners) >= 0.0);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    kg::TruthScene scene;
    std::string error;
    if (kg::parse_truth_line(text.substr(begin, end - begin), scene, error)) {
      exercise(scene);
    } else {
      check(!error.empty());
    }
    begin = end + 1;
  }
  kg::TruthManifest manifest;
  const kg::Status s = kg::parse_truth_manifest(text, "dir/m.jsonl", manifest);
  if (!s) {
    check(s.message().rfind("dir/m.jsonl", 0) == 0);
  } else {
    check(!manifest.scenes.empty());
    for (const kg::TruthScene& scene : manifest.scenes) {
      check(scene.line >= 1 && scene.path.find(scene.scene) != std::string::npos);
      exercise(scene);
    }
  }
  return 0;
}
