// Output shared by the device commands (detect on files, live): one frame's
// detections as text or as the JSON line of `keygraph detect --json`, and
// the detections drawn into a gray copy of the frame, for PGM files.
#pragma once

#include <string>

#include "cli/device/json.h"
#include "keygraph/detector.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "platform/files/pgm.h"

namespace kg::cli {

// Empty when the core Detector can run on `index` with its built-in
// keypoint detector; otherwise why not, for an error line.
std::string core_detector_problem(const ModelIndex& index);

// Prints one frame's result on stdout: the JSON line of cli/device/json.h,
// or "NAME: K detection(s) in T ms" and a line per detection. With
// `tracked` (keygraph live), each detection's track too, and "tracked" after
// the time of a frame on which no detection ran.
void print_detections(const std::string& name, const ImageView& frame, double ms,
                      const DetectionList& found, const DetectStats& stats, bool json,
                      const TrackedFrame* tracked = nullptr);

// A scene that could not be read or detected on: one error line (fail()),
// and with `json` also its line {"scene": ..., "error": ...} on stdout, so
// that stdout keeps one line per scene. Returns 1.
int scene_failed(const std::string& scene, const std::string& message, bool json);

// Where a detection's name goes in a picture of `width` x `height`: the
// bottom-left corner (OpenCV's text origin) of a text `text_width` wide,
// `text_height` high above that corner and `baseline` below it. Above the
// detection's topmost corner, below it when that is too close to the top,
// then moved inside the picture, so that a detection at an edge, or upside
// down (its first corner at the bottom right), keeps its whole name.
struct LabelPosition {
  int x = 0, y = 0;
};
LabelPosition label_position(const Detection& d, int width, int height, int text_width,
                             int text_height, int baseline);

// Copies `frame` into `canvas` (its capacity reused) and draws each
// detection's outline (a white line with a black edge, 3 pixels wide, so it
// shows on any background) and its model's name (bitmap_font.h), placed as
// label_position() says.
void draw_outlines(const ImageView& frame, const DetectionList& found, platform::GrayImage& canvas);

}  // namespace kg::cli
