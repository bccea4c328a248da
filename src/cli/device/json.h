// Minimal JSON writing for the CLI's line-oriented output.
#pragma once

#include <string>
#include <string_view>

#include "keygraph/detector.h"

namespace kg::cli {

// A JSON string of `s`: quotes, backslashes and control characters escaped;
// bytes that are not UTF-8 (a file name in another encoding) become U+FFFD,
// so the line stays valid JSON.
std::string json_string(std::string_view s);
std::string json_number(double v);
// One line: {"scene": ..., "width": ..., "detections": [...], "stats": {...}}.
std::string detection_json(const std::string& scene, int width, int height, double time_ms,
                           const DetectionList& detections, const DetectStats& stats);
// The line for a scene that could not be read or detected on:
// {"scene": ..., "error": "..."}, so that a consumer gets one line per scene.
std::string scene_error_json(const std::string& scene, const std::string& error);

}  // namespace kg::cli
