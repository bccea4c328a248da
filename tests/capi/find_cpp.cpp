// The reference for the bindings' programs: the C++ API on the same index
// and PGM frames, printing what they print (tests/capi/find.c says the
// format), so that compare_find.py can hold them to the same corners.
//   kg_find_cpp INDEX FRAME.pgm...
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "keygraph/detector.h"
#include "keygraph/model_index.h"
#include "platform/files/pgm.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: kg_find_cpp INDEX FRAME.pgm...\n");
    return 2;
  }
  kg::ModelIndex index;
  if (kg::Status s = kg::ModelIndex::read(argv[1], index); !s) {
    std::fprintf(stderr, "kg_find_cpp: %s\n", s.message().c_str());
    return 1;
  }
  std::vector<kg::platform::GrayImage> frames(static_cast<std::size_t>(argc - 2));
  int max_width = 1, max_height = 1;
  for (int i = 2; i < argc; ++i) {
    kg::platform::GrayImage& frame = frames[static_cast<std::size_t>(i - 2)];
    if (kg::Status s = kg::platform::read_pgm(argv[i], frame); !s) {
      std::fprintf(stderr, "kg_find_cpp: %s\n", s.message().c_str());
      return 1;
    }
    max_width = std::max(max_width, frame.width);
    max_height = std::max(max_height, frame.height);
  }
  kg::Detector detector(index, kg::Limits{}.for_frame(max_width, max_height));
  if (!detector.status()) {
    std::fprintf(stderr, "kg_find_cpp: %s\n", detector.status().message().c_str());
    return 1;
  }
  kg::DetectionList found;
  for (int i = 2; i < argc; ++i) {
    const std::string name = std::filesystem::path(argv[i]).filename().string();
    if (kg::Status s = detector.detect(frames[static_cast<std::size_t>(i - 2)].view(), found); !s) {
      std::fprintf(stderr, "kg_find_cpp: %s: %s\n", name.c_str(), s.message().c_str());
      return 1;
    }
    if (found.empty()) std::printf("%s none\n", name.c_str());
    for (const kg::Detection& d : found) {
      std::printf("%s %.*s", name.c_str(), static_cast<int>(d.model_name.size()),
                  d.model_name.data());
      for (const kg::Point2f& c : d.corners) std::printf(" %.4f %.4f", double{c.x}, double{c.y});
      std::printf(" inliers=%d confidence=%.4f\n", d.inliers, d.confidence);
    }
  }
  return 0;
}
