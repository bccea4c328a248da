// Opens a model index, builds a detector on it and runs one detection on a
// synthetic gray frame. Shows the smallest use of the installed runtime core
// (keygraph::core, or `pkg-config --cflags --libs keygraph`).
//
//   keygraph build box.png -o box.kgi
//   keygraph_example box.kgi
#include <cstdint>
#include <cstdio>
#include <vector>

#include <keygraph/detector.h>
#include <keygraph/image.h>
#include <keygraph/model_index.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s INDEX.kgi\n", argc > 0 ? argv[0] : "keygraph_example");
    return 2;
  }

  kg::ModelIndex index;
  if (kg::Status s = kg::ModelIndex::open(argv[1], index); !s) {
    std::fprintf(stderr, "keygraph_example: %s\n", s.message().c_str());
    return 1;
  }

  // A 320x240 diagonal gradient stands in for a camera frame.
  const int width = 320;
  const int height = 240;
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      pixels[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>((x + y) * 255 / (width + height - 2));
    }
  }

  kg::Detector detector(index);  // allocates its buffers here, once
  kg::DetectionList found;
  if (kg::Status s = detector.detect(kg::ImageView{pixels.data(), width, height}, found); !s) {
    std::fprintf(stderr, "keygraph_example: %s\n", s.message().c_str());
    return 1;
  }

  std::printf("models: %d\n", index.model_count());
  std::printf("detections: %zu\n", found.size());
  return 0;
}
