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
// What `keygraph live` adds to a frame's line when it tracks: "detected"
// after "time_ms" (false when every object was followed from the frame
// before and no detection ran: the stats are then all zero), and "track"
// (the id, -1 when not followed) and "tracked" (confirmed around its
// prediction) in each detection.
struct TrackedFrame {
  bool detected = true;
};
// One line: {"scene": ..., "width": ..., "detections": [...], "stats": {...}}
// (the stats end with "stopped_early": the stage a time budget ran out in,
// or null);
// with `tracked`, its additions too.
std::string detection_json(const std::string& scene, int width, int height, double time_ms,
                           const DetectionList& detections, const DetectStats& stats,
                           const TrackedFrame* tracked = nullptr);
// The line for a scene that could not be read or detected on:
// {"scene": ..., "error": "..."}, so that a consumer gets one line per scene.
std::string scene_error_json(const std::string& scene, const std::string& error);

}  // namespace kg::cli
