// libFuzzer target for the exit-signs corners.txt reader of `keygraph
// manifest` (eval/set_files.h, docs/EVAL.md): each input is a file's text.
// Every sign it accepts has an image name without control characters or
// spaces, an index in 0..1000000, and four finite corners within 1e7 that
// form a simple quadrilateral (what eval --truth requires of a manifest);
// what it refuses is an error naming the file and line.
//
// Seeds: tests/fuzz/seeds/corners/.
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_corners
//   build/fuzz/tests/fuzz/fuzz_corners CORPUS_DIR tests/fuzz/seeds/corners -max_total_time=60
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "eval/quad_geometry.h"
#include "eval/set_files.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<kg::MarkedSign> signs;
  const kg::Status s = kg::parse_corners_text(text, "corners.txt", signs);
  if (!s) {
    check(s.message().rfind("corners.txt:", 0) == 0);
    return 0;
  }
  for (const kg::MarkedSign& sign : signs) {
    check(!sign.image.empty());
    for (const char c : sign.image) check(static_cast<unsigned char>(c) > 0x20 && c != 0x7f);
    check(sign.index >= 0 && sign.index <= 1000000);
    kg::Point2f quad[4];
    for (int c = 0; c < 4; ++c) {
      const double x = sign.corners[2 * c], y = sign.corners[2 * c + 1];
      check(std::isfinite(x) && std::isfinite(y) && std::fabs(x) <= 1e7 && std::fabs(y) <= 1e7);
      quad[c] = {static_cast<float>(x), static_cast<float>(y)};
    }
    check(kg::is_simple_quad(quad));
  }
  return 0;
}
