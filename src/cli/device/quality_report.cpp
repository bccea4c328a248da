#include "cli/device/quality_report.h"

#include <algorithm>
#include <cinttypes>
#include <string>

namespace kg::cli {

namespace {

std::string model_name(const ModelIndex& index, std::uint32_t m) {
  const ModelInfo info = index.model(static_cast<int>(m));
  return std::string(info.name);
}

std::string stars_text(int stars) {
  std::string text;
  for (int i = 0; i < 5; ++i) text += i < stars ? '*' : '.';
  return text;
}

// The reader keeps the pairs sorted by (shown, detected) and unrepeated: a
// binary search, so that a hostile index with every pair listed costs
// O(pairs log pairs) per model, not O(pairs^2).
bool has_pair(const ModelIndex& index, std::uint32_t shown, std::uint32_t detected) {
  std::uint32_t lo = 0, hi = index.look_alike_count();
  while (lo < hi) {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    const LookAlike p = index.look_alike(mid);
    if (p.shown < shown || (p.shown == shown && p.detected < detected)) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  if (lo == index.look_alike_count()) return false;
  const LookAlike p = index.look_alike(lo);
  return p.shown == shown && p.detected == detected;
}

}  // namespace

ModelRating rate_model(const ModelIndex& index, int m) {
  ModelRating r;
  const ModelInfo info = index.model(m);
  const ModelQuality q = index.model_quality(m);
  const Params& params = index.params();
  const ViewQuality full = q.view_count > 0 ? index.view_quality(q.view_begin) : ViewQuality{};
  int stars = 5;
  if (q.smallest_size <= 0.f) {
    stars = 0;
    r.warnings.push_back("too few keypoints or keygraphs to be found at any size (" +
                         std::to_string(full.keypoints) + " keypoints, " +
                         std::to_string(full.keygraphs) + " keygraphs at full size; a detection" +
                         " needs " + std::to_string(params.ransac.min_inliers) + " and " +
                         std::to_string(params.ransac.min_inlier_keygraphs) + " of them to match)");
  } else if (params.views.min_size <= 0.f) {
    // One view (the model image): nothing says how small it can get.
    r.warnings.push_back("smallest size not measured (built without views: --min-size 0)");
  } else if (q.smallest_size > kLargeOnlySize) {
    stars -= q.smallest_size > 2.f * kLargeOnlySize ? 2 : 1;
    r.warnings.push_back("can only be found when large (long edge >= " +
                         std::to_string(static_cast<int>(q.smallest_size)) + " px in the frame)");
  }
  const double shared =
      info.arc_count > 0 ? static_cast<double>(q.shared_arcs) / info.arc_count : 0.0;
  if (shared > kMaxSharedFraction) {
    stars -= 1;
    r.warnings.push_back("low distinctiveness (" + std::to_string(static_cast<int>(100 * shared)) +
                         " % of its arcs are near-identical to other models' arcs)");
  }
  if (q.scene_size > 0.f && !q.found_in_scene) {
    stars -= 2;
    r.warnings.push_back("not found in its own test scene (" +
                         std::to_string(static_cast<int>(q.scene_size)) +
                         " px, mildly tilted, on grey)");
  }
  bool confusable = false;
  for (std::uint32_t i = 0; i < index.look_alike_count(); ++i) {
    const LookAlike p = index.look_alike(i);
    const auto self = static_cast<std::uint32_t>(m);
    if (p.shown == self) {
      r.warnings.push_back("look-alike of " + model_name(index, p.detected) + " (" +
                           model_name(index, p.detected) + " is detected in its scene)");
      confusable = true;
    } else if (p.detected == self && !has_pair(index, self, p.shown)) {  // else named above
      r.warnings.push_back("look-alike of " + model_name(index, p.shown) + " (detected in " +
                           model_name(index, p.shown) + "'s scene)");
      confusable = true;
    }
  }
  if (confusable) stars -= 1;
  r.stars = std::clamp(stars, 0, 5);
  r.grade = r.stars >= 4 ? "good" : r.stars >= 2 ? "fair" : "weak";
  return r;
}

void print_quality_report(const ModelIndex& index, bool with_views, std::FILE* out) {
  if (!index.has_quality()) {
    std::fprintf(out,
                 "\nquality: no report in this index (written by format %u.%u or without "
                 "one; rebuild with keygraph build)\n",
                 index.version_major(), index.version_minor());
    return;
  }
  const bool scenes = index.model_count() > 0 && index.model_quality(0).scene_size > 0.f;
  std::fprintf(out,
               "\nquality (docs/QUALITY.md): keypoints and keygraphs at full size, smallest long "
               "edge found, arcs near-identical to other models'%s\n",
               scenes ? ", found in its own scene" : "");
  std::fprintf(out, "  %3s  %-20s %5s %-5s %9s %9s %8s %7s %6s\n", "#", "name", "stars", "grade",
               "keypoints", "keygraphs", "smallest", "shared", "scene");
  int total_stars = 0, lowest = 5, good = 0, fair = 0, weak = 0;
  std::vector<std::string> warnings;
  for (int m = 0; m < index.model_count(); ++m) {
    const ModelInfo info = index.model(m);
    const ModelQuality q = index.model_quality(m);
    const ViewQuality full = q.view_count > 0 ? index.view_quality(q.view_begin) : ViewQuality{};
    const ModelRating r = rate_model(index, m);
    total_stars += r.stars;
    lowest = std::min(lowest, r.stars);
    (r.stars >= 4 ? good : r.stars >= 2 ? fair : weak) += 1;
    const double shared =
        info.arc_count > 0 ? 100.0 * q.shared_arcs / static_cast<double>(info.arc_count) : 0.0;
    char smallest[16];
    if (q.smallest_size > 0.f) {
      std::snprintf(smallest, sizeof(smallest), "%.0f px", static_cast<double>(q.smallest_size));
    } else {
      std::snprintf(smallest, sizeof(smallest), "never");
    }
    std::fprintf(out, "  %3d  %-20.*s %5s %-5s %9u %9u %8s %6.1f%% %6s\n", m,
                 static_cast<int>(info.name.size()), info.name.data(), stars_text(r.stars).c_str(),
                 r.grade, full.keypoints, full.keygraphs, smallest, shared,
                 q.scene_size <= 0.f ? "-"
                 : q.found_in_scene  ? "found"
                                     : "MISSED");
    if (with_views) {
      for (std::uint32_t v = q.view_begin; v < q.view_begin + q.view_count; ++v) {
        const ViewQuality vq = index.view_quality(v);
        // The frontal long edge at the view's scale (a tilt shortens one side).
        const double edge = static_cast<double>(vq.scale) * std::max(info.width, info.height);
        std::fprintf(
            out,
            "         view %4.0f px (scale %.3f, tilt %.2f, longitude %5.1f): %u keypoints, "
            "%u arcs, %u keygraphs\n",
            edge, static_cast<double>(vq.scale), static_cast<double>(vq.tilt),
            static_cast<double>(vq.longitude), vq.keypoints, vq.arcs, vq.keygraphs);
      }
    }
    for (const std::string& w : r.warnings) warnings.push_back(std::string(info.name) + ": " + w);
  }
  std::fprintf(out, "\nlook-alikes (model shown -> model detected in its scene): %u\n",
               index.look_alike_count());
  for (std::uint32_t i = 0; i < index.look_alike_count(); ++i) {
    const LookAlike p = index.look_alike(i);
    std::fprintf(out, "  %s -> %s\n", model_name(index, p.shown).c_str(),
                 model_name(index, p.detected).c_str());
  }
  for (const std::string& w : warnings) std::fprintf(out, "warning: %s\n", w.c_str());
  const int n = index.model_count();
  // The index: good when every model is good and none is confused with
  // another, weak when more than a tenth of its models are weak.
  const char* grade = weak * 10 > n                                  ? "weak"
                      : (good == n && index.look_alike_count() == 0) ? "good"
                                                                     : "fair";
  std::fprintf(out,
               "index rating: %s; %.1f stars on average, lowest %d; %d good, %d fair, %d weak; "
               "%u look-alike detections%s\n",
               grade, n > 0 ? static_cast<double>(total_stars) / n : 0.0, n > 0 ? lowest : 0, good,
               fair, weak, index.look_alike_count(), scenes ? "" : " (look-alike check not run)");
}

}  // namespace kg::cli
