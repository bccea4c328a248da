#include "cli/device/frame_output.h"

#include "cli/device/bitmap_font.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cli/device/bitmap_font.h"
#include "cli/device/command_line.h"
#include "cli/device/json.h"
#include "platform/convert.h"

namespace kg::cli {

std::string core_detector_problem(const ModelIndex& index) {
  // The desktop keygraph's live and bench (and every command of the device
  // keygraph) detect with the core alone, as a device does: keypoints from
  // its own detector (hessian), no vertex descriptors.
#if KG_CLI_DEVICE_ONLY
  const char* why = "which needs OpenCV (not in this build of keygraph)";
  const char* instead = "";
#else
  const char* why = "which the core detector lacks (this command runs it alone, as a device does)";
  const char* instead = ", or use keygraph detect";
#endif
  const Params& p = index.params();
  if (p.keypoints.detector != KeypointDetector::kHessian) {
    return std::string("the index was built with --detector mser, ") + why +
           "; build it with the default detector (hessian) to detect with the core" + instead;
  }
  if (p.descriptor.vertex_descriptor != VertexDescriptor::kNone) {
    return std::string("the index was built with --vertex-descriptor sift, ") + why +
           "; build it without vertex descriptors to detect with the core" + instead;
  }
  return {};
}

void print_detections(const std::string& name, const ImageView& frame, double ms,
                      const DetectionList& found, const DetectStats& stats, bool json,
                      const TrackedFrame* tracked) {
  if (json) {
    std::printf("%s\n",
                detection_json(name, frame.width, frame.height, ms, found, stats, tracked).c_str());
    return;
  }
  std::printf("%s: %zu detection(s) in %.1f ms%s", name.c_str(), found.size(), ms,
              tracked != nullptr && !tracked->detected ? ", tracked" : "");
  if (stats.stopped_early != nullptr)
    std::printf(" (stopped early: time budget spent in the %s)", stats.stopped_early);
  std::printf("\n");
  for (const Detection& d : found) {
    std::printf("  %.*s: inliers %d, score %.3f, appearance %.2f, confidence %.2f, corners",
                static_cast<int>(d.model_name.size()), d.model_name.data(), d.inliers, d.score,
                d.appearance, d.confidence);
    for (const Point2f& c : d.corners) std::printf(" (%.1f, %.1f)", c.x, c.y);
    if (tracked != nullptr) std::printf(", track %d%s", d.track_id, d.tracked ? " (tracked)" : "");
    std::printf("\n");
  }
}

int scene_failed(const std::string& scene, const std::string& message, bool json) {
  if (json) std::printf("%s\n", scene_error_json(scene, message).c_str());
  return fail(message);
}

LabelPosition label_position(const Detection& d, int width, int height, int text_width,
                             int text_height, int baseline) {
  const Point2f* top = &d.corners[0];
  for (const Point2f& c : d.corners) {
    if (c.y < top->y || (c.y == top->y && c.x < top->x)) top = &c;
  }
  const int margin = 4;
  const auto whole = [](float v) {
    return static_cast<int>(std::lround(std::clamp(static_cast<double>(v), -1e6, 1e6)));
  };
  const int top_x = whole(top->x), top_y = whole(top->y);
  int y = top_y - margin - baseline;                               // above the corner
  if (y - text_height < margin) y = top_y + margin + text_height;  // or below it
  // Inside the picture (at its left or top edge when the name is larger).
  LabelPosition at;
  at.x = std::clamp(top_x, margin, std::max(margin, width - text_width - margin));
  at.y = std::clamp(y, margin + text_height,
                    std::max(margin + text_height, height - baseline - margin));
  return at;
}

namespace {

// A square brush of half-width r centred on (x, y), clipped to the image.
void stamp(platform::GrayImage& img, long x, long y, int r, std::uint8_t value) {
  for (long yy = std::max(0L, y - r); yy <= std::min<long>(img.height - 1, y + r); ++yy) {
    for (long xx = std::max(0L, x - r); xx <= std::min<long>(img.width - 1, x + r); ++xx) {
      img.pixels[static_cast<std::size_t>(yy) * static_cast<std::size_t>(img.width) +
                 static_cast<std::size_t>(xx)] = value;
    }
  }
}

// Bresenham from a to b. Endpoints far outside the frame (a wild pose) are
// clamped first so the loop stays short; the visible part of a line whose
// ends are clamped can shift, which is fine for a picture.
void line(platform::GrayImage& img, Point2f a, Point2f b, int r, std::uint8_t value) {
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
    return;
  const double limit = 4.0 * std::max(img.width, img.height);
  auto clamp = [limit](float v) {
    return std::lround(std::clamp(static_cast<double>(v), -limit, limit));
  };
  long x0 = clamp(a.x), y0 = clamp(a.y);
  const long x1 = clamp(b.x), y1 = clamp(b.y);
  const long dx = std::labs(x1 - x0), dy = -std::labs(y1 - y0);
  const long sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  long err = dx + dy;
  for (;;) {
    stamp(img, x0, y0, r, value);
    if (x0 == x1 && y0 == y1) break;
    const long e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

}  // namespace

void draw_outlines(const ImageView& frame, const DetectionList& found,
                   platform::GrayImage& canvas) {
  canvas.width = frame.width;
  canvas.height = frame.height;
  canvas.pixels.resize(static_cast<std::size_t>(frame.width) *
                       static_cast<std::size_t>(frame.height));
  platform::copy_gray(frame, canvas.pixels.data(), frame.width);
  // Black 5 pixels wide first, then white 3 pixels wide on top.
  for (const Detection& d : found) {
    for (int i = 0; i < 4; ++i) line(canvas, d.corners[i], d.corners[(i + 1) % 4], 2, 0);
  }
  for (const Detection& d : found) {
    for (int i = 0; i < 4; ++i) line(canvas, d.corners[i], d.corners[(i + 1) % 4], 1, 255);
  }
  // The names last, over every outline, as the desktop detect draws them:
  // twice the font's size at 480 lines (readable at a glance), more above.
  const int scale = std::max(1, std::min(frame.width, frame.height) / 240);
  for (const Detection& d : found) {
    const std::string_view name(d.model_name);
    const LabelPosition at = label_position(d, canvas.width, canvas.height, text_width(name, scale),
                                            kGlyphHeight * scale, 0);
    draw_text(canvas, name, at.x, at.y, scale, 255, 0);
  }
}

}  // namespace kg::cli
