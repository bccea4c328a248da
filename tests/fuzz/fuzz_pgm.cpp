// libFuzzer target for the PGM reader (platform/files/pgm.h), the device
// build's only image decoder: each input is a candidate .pgm file, decoded
// from a buffer of exactly its size (so AddressSanitizer sees any read past
// its end). A decoded image must have the size its header declares, within
// the limits (image_limits.h), and pixels for all of it; the JPEG structure
// check (jpeg_structure.h) and the header size reader of every other format
// (image_header.h, at each reduction of JPEG's reduced decoding) run on the
// same bytes.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "platform/files/image_header.h"
#include "platform/files/image_limits.h"
#include "platform/files/jpeg_structure.h"
#include "platform/files/pgm.h"

namespace {

void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_pgm: decoded image breaks a reader guarantee: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  kg::platform::GrayImage image;
  const kg::Status s = kg::platform::decode_pgm(bytes.data(), bytes.size(), "fuzz.pgm", image);
  if (s) {
    require(image.width >= 1 && image.height >= 1, "empty image");
    require(static_cast<long long>(image.width) * image.height <= kg::platform::kMaxImagePixels,
            "over the pixel limit");
    require(image.pixels.size() == static_cast<std::size_t>(image.width) * image.height,
            "pixel count differs from the size");
    // The samples came from the input: the file holds at least one byte each.
    require(image.pixels.size() <= size, "more pixels than input bytes");
    unsigned sum = 0;
    for (std::uint8_t p : image.pixels) sum += p;  // reads every pixel
    (void)sum;
  } else {
    require(!s.message().empty(), "error without a message");
  }
  if (kg::platform::is_jpeg(bytes.data(), bytes.size()))
    (void)kg::platform::jpeg_is_complete(bytes.data(), bytes.size());
  const kg::platform::DeclaredSize declared =
      kg::platform::declared_image_size(bytes.data(), bytes.size());
  require(declared.kind != kg::platform::DeclaredSize::kKnown ||
              (declared.width > 0 && declared.height > 0),
          "a known declared size of zero");
  for (int reduction : {1, 2, 4, 8}) {
    const kg::Status checked = kg::platform::check_declared_size(bytes, "fuzz", reduction);
    require(checked || !checked.message().empty(), "a refused size without a message");
  }
  return 0;
}
