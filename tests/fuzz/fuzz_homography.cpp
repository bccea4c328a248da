// libFuzzer target for the homography files of the photo sets
// (planar-pairs' NAME_H_A_to_B.txt, the Oxford set's H1toNp;
// eval/set_files.h): each input is a file's text. What it accepts is 9
// finite numbers that normalise to h33 = 1 in finite, invertible numbers
// (what eval --truth requires of a manifest's homography), and it maps
// points without a fault; what it refuses is an error naming the file.
//
// Seeds: tests/fuzz/seeds/homography/.
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_homography
//   build/fuzz/tests/fuzz/fuzz_homography CORPUS_DIR tests/fuzz/seeds/homography \
//     -max_total_time=60
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "eval/quad_geometry.h"
#include "eval/set_files.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  kg::Homography h{};
  const kg::Status s = kg::parse_homography_text(text, "H.txt", h);
  if (!s) {
    check(s.message().rfind("H.txt: ", 0) == 0);
    return 0;
  }
  for (const double v : h) check(std::isfinite(v));
  kg::Homography normalised = h;
  check(kg::normalise_homography(normalised));
  check(normalised[8] == 1.0);
  // Mapping a point must not fault (it may leave the finite numbers: a
  // point on the line at infinity).
  const kg::Point2f p = kg::apply(normalised, kg::Point2f{10.f, 20.f});
  (void)p;
  return 0;
}
