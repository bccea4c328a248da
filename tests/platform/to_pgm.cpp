// kg_to_pgm IN OUT.pgm: any image OpenCV reads, as 8-bit gray binary PGM
// written by platform/files (test input for the PGM path of the CLI).
#include <cstdio>

#include <opencv2/imgcodecs.hpp>

#include "platform/files/pgm.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: kg_to_pgm IN OUT.pgm\n");
    return 2;
  }
  const cv::Mat gray = cv::imread(argv[1], cv::IMREAD_GRAYSCALE);
  if (gray.empty()) {
    std::fprintf(stderr, "kg_to_pgm: cannot read %s\n", argv[1]);
    return 1;
  }
  const kg::ImageView view(gray.data, gray.cols, gray.rows, static_cast<std::ptrdiff_t>(gray.step));
  if (kg::Status s = kg::platform::write_pgm(argv[2], view); !s) {
    std::fprintf(stderr, "kg_to_pgm: %s\n", s.message().c_str());
    return 1;
  }
  return 0;
}
