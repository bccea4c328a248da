#include "cli/device/json.h"

#include <cmath>
#include <cstdio>
#include <utility>

namespace kg::cli {

namespace {

// The length of the well-formed UTF-8 sequence at s[i] (1..4), or 0 when
// it is not one (a stray continuation byte, a truncated or overlong
// sequence, a surrogate, a code point above U+10FFFF).
std::size_t utf8_sequence(std::string_view s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char lead = byte(i);
  if (lead < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the allowed range of the second byte
  if (lead >= 0xC2 && lead <= 0xDF) {
    n = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    n = 3;
    if (lead == 0xE0) lo = 0xA0;  // no overlong forms
    if (lead == 0xED) hi = 0x9F;  // no surrogates
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    n = 4;
    if (lead == 0xF0) lo = 0x90;  // no overlong forms
    if (lead == 0xF4) hi = 0x8F;  // nothing above U+10FFFF
  } else {
    return 0;
  }
  if (i + n > s.size() || byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return n;
}

}  // namespace

std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c >= 0x80) {
      const std::size_t n = utf8_sequence(s, i);
      if (n == 0) {
        out += "\\ufffd";  // one replacement character per byte that is not UTF-8
        ++i;
      } else {
        out.append(s.substr(i, n));
        i += n;
      }
      continue;
    }
    ++i;
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

std::string detection_json(const std::string& scene, int width, int height, double time_ms,
                           const DetectionList& detections, const DetectStats& stats,
                           const TrackedFrame* tracked) {
  std::string s = "{\"scene\": " + json_string(scene) + ", \"width\": " + std::to_string(width) +
                  ", \"height\": " + std::to_string(height) +
                  ", \"time_ms\": " + json_number(std::round(time_ms * 1000.0) / 1000.0) +
                  (tracked == nullptr  ? ""
                   : tracked->detected ? ", \"detected\": true"
                                       : ", \"detected\": false") +
                  ", \"detections\": [";
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const Detection& d = detections[i];
    if (i > 0) s += ", ";
    s += "{\"model\": " + json_string(d.model_name) +
         ", \"model_id\": " + std::to_string(d.model_id) + ", \"homography\": [";
    for (int j = 0; j < 9; ++j) s += (j ? ", " : "") + json_number(d.homography[j]);
    s += "], \"corners\": [";
    for (int c = 0; c < 4; ++c) {
      s += (c ? ", [" : "[") + json_number(d.corners[c].x) + ", " + json_number(d.corners[c].y) +
           "]";
    }
    s += "], \"inliers\": " + std::to_string(d.inliers) + ", \"score\": " + json_number(d.score) +
         ", \"appearance\": " + json_number(d.appearance) +
         ", \"confidence\": " + json_number(d.confidence);
    if (tracked != nullptr) {
      s += ", \"track\": " + std::to_string(d.track_id) +
           ", \"tracked\": " + (d.tracked ? "true" : "false");
    }
    s += "}";
  }
  s += "], \"stats\": {\"keypoints\": " + std::to_string(stats.keypoints) +
       ", \"sampled_keypoints\": " + std::to_string(stats.sampled_keypoints) +
       ", \"keygraphs\": " + std::to_string(stats.keygraphs) +
       ", \"arc_matches\": " + std::to_string(stats.arc_matches) +
       ", \"correspondences\": " + std::to_string(stats.correspondences) +
       ", \"patch_rejections\": " + std::to_string(stats.patch_rejections) +
       ", \"completion\": {\"tried\": " + std::to_string(stats.completion_tried) +
       ", \"clockwise\": " + std::to_string(stats.completion_clockwise) +
       ", \"plausible\": " + std::to_string(stats.completion_plausible) +
       ", \"closed\": " + std::to_string(stats.completion_closed) + "}" +
       ", \"ransac_iterations\": " + std::to_string(stats.ransac_iterations) + ", \"truncated\": [";
  // Which per-frame capacity (Limits) was reached: detection degraded there.
  const std::pair<bool, const char*> cuts[] = {{stats.truncated_keypoints, "keypoints"},
                                               {stats.truncated_arc_matches, "arc_matches"},
                                               {stats.truncated_correspondences, "correspondences"},
                                               {stats.truncated_detections, "detections"}};
  bool first = true;
  for (const auto& [cut, name] : cuts) {
    if (!cut) continue;
    s += (first ? "" : ", ") + json_string(name);
    first = false;
  }
  // The stage a time budget (--set time_budget_ms) ran out in.
  s += "], \"stopped_early\": " +
       (stats.stopped_early == nullptr ? std::string("null") : json_string(stats.stopped_early));
  s += "}}";
  return s;
}

std::string scene_error_json(const std::string& scene, const std::string& error) {
  return "{\"scene\": " + json_string(scene) + ", \"error\": " + json_string(error) + "}";
}

}  // namespace kg::cli
