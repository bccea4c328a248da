// Minimal JSON writing for the CLI's line-oriented output.
#pragma once

#include <string>
#include <string_view>

#include "keygraph/detector.h"

namespace kg::cli {

std::string json_string(std::string_view s);
std::string json_number(double v);
// One line: {"scene": ..., "width": ..., "detections": [...], "stats": {...}}.
std::string detection_json(const std::string& scene, int width, int height, double time_ms,
                           const DetectionList& detections, const DetectStats& stats);

}  // namespace kg::cli
