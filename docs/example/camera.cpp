// The shape of a device application: open a model index, size a
// detector for the source's frames, then detect on every frame of a frame source, here a V4L2
// camera or a directory of PGM images (keygraph::v4l2, keygraph::files).
// Nothing is allocated per frame by the detector or the sources; frames are
// views of the capture buffers. The detector's workspace is sized for the
// frames it gets (kg::Limits, 640x480 by default): a larger frame is an
// error, not a resize, so the detector is made once the source's frame size
// is known, and again only for a larger frame (files of several sizes).
//
//   keygraph_camera_example signs.kgi /dev/video0 [FRAMES]
//   keygraph_camera_example signs.kgi frames/ [FRAMES]
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

#include <keygraph/detector.h>
#include <keygraph/model_index.h>
#include <keygraph/platform/files/file_source.h>
#include <keygraph/platform/frame_source.h>
#include <keygraph/platform/v4l2/v4l2_source.h>

namespace {

int fail(const std::string& message) {
  std::fprintf(stderr, "keygraph_camera_example: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: %s INDEX.kgi (/dev/videoN | FRAME_DIR) [FRAMES]\n",
                 argc > 0 ? argv[0] : "keygraph_camera_example");
    return 2;
  }
  const std::string source_name = argv[2];
  const long max_frames = argc == 4 ? std::strtol(argv[3], nullptr, 10) : 100;

  kg::ModelIndex index;
  if (kg::Status s = kg::ModelIndex::open(argv[1], index); !s) return fail(s.message());
  std::optional<kg::Detector> detector;  // made for the first frame's size
  kg::DetectionList found;

  std::unique_ptr<kg::platform::FrameSource> source;
  if (source_name.rfind("/dev/", 0) == 0) {
    kg::platform::V4l2Options options;
    options.device = source_name;  // 640x480 requested; the driver picks the nearest
    source = std::make_unique<kg::platform::V4l2Source>(options);
  } else {
    source = std::make_unique<kg::platform::FileSource>(std::vector<std::string>{source_name});
  }
  if (kg::Status s = source->start(); !s) return fail(s.message());
  std::printf("source: %s\n", source->description().c_str());

  int exit_code = 0;
  for (long n = 0; n < max_frames;) {
    kg::platform::Frame frame;
    const kg::Status s = source->next(frame, 1000);
    if (kg::platform::is_end_of_stream(s)) break;
    if (kg::platform::is_timeout(s) || kg::platform::is_bad_frame(s)) {
      std::fprintf(stderr, "keygraph_camera_example: %s (skipped)\n", s.message().c_str());
      continue;
    }
    if (!s) {
      exit_code = fail(s.message());
      break;
    }
    const kg::ImageView& image = frame.image;
    if (!detector || image.width > detector->limits().max_width ||
        image.height > detector->limits().max_height) {
      // The one line that sizes the detector for its source (allocates here):
      detector.emplace(index, kg::Limits{}.for_frame(image.width, image.height));
      if (!detector->status()) {
        exit_code = fail(detector->status().message());
        break;
      }
    }
    if (kg::Status d = detector->detect(image, found); !d) {
      exit_code = fail(d.message());
      break;
    }
    std::printf("frame %llu (%dx%d): %zu detection(s)\n",
                static_cast<unsigned long long>(frame.sequence), frame.image.width,
                frame.image.height, found.size());
    for (const kg::Detection& d : found) {
      std::printf("  %.*s, corners", static_cast<int>(d.model_name.size()), d.model_name.data());
      for (const kg::Point2f& c : d.corners) std::printf(" (%.1f, %.1f)", c.x, c.y);
      std::printf("\n");
    }
    ++n;
  }
  source->stop();
  return exit_code;
}
