// Hostile input: real model indexes (box.png, and a crop of graf1.png),
// serialised in memory and damaged blindly -- truncated and extended, bit-
// flipped, overwritten, and spliced with chunks of each other -- several
// thousand mutants in all. Each must either be rejected with an error Status
// or load and run detect() on box_in_scene.png without fault. Faults are what
// the `sanitize` preset's AddressSanitizer and UBSan catch: every mutant sits
// in a buffer of exactly its size, so a read past its end is reported.
//
// Only the public API (ModelIndex::view, Detector), serialize_index and
// measure_quality are used, and no mutation knows the layout (docs/FORMAT.md): positions are
// chosen densely over the first bytes of a file (where any layout keeps its
// fixed-size structures) and at random over the rest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "builder/model_quality.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"
#include "support/test_data.h"

namespace kg {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::size_t kAlignment = 64;  // ModelIndex::view's requirement

// A copy of `bytes` in a 64-byte aligned allocation of exactly its size.
class AlignedCopy {
 public:
  explicit AlignedCopy(const Bytes& bytes) : size_(bytes.size()) {
    data_ = static_cast<std::uint8_t*>(
        ::operator new[](std::max<std::size_t>(size_, 1), std::align_val_t(kAlignment)));
    if (size_ > 0) std::memcpy(data_, bytes.data(), size_);
  }
  ~AlignedCopy() { ::operator delete[](data_, std::align_val_t(kAlignment)); }
  AlignedCopy(const AlignedCopy&) = delete;
  AlignedCopy& operator=(const AlignedCopy&) = delete;
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

// Real indexes, built once per test program (each TEST runs in its own
// process under ctest).
struct Corpus {
  Bytes box;   // box.png, default parameters
  Bytes graf;  // 200x200 crop of graf1.png at (250, 200), default parameters
  cv::Mat scene;
};

Bytes build_index(const cv::Mat& gray, const std::string& name) {
  Params params;
  BuiltModel model;
  Status s = build_model(gray, name, params, model);
  EXPECT_TRUE(s.is_ok()) << s.message();
  // With the quality report keygraph build stores (format 6.1) and the
  // appearance the default parameters ask for (6.2).
  QualityReport quality;
  s = measure_quality({model}, {gray}, params, QualityOptions{}, quality);
  EXPECT_TRUE(s.is_ok()) << s.message();
  Bytes bytes;
  s = serialize_index({model}, params, bytes, &quality);
  EXPECT_TRUE(s.is_ok()) << s.message();
  return bytes;
}

const Corpus& corpus() {
  static const Corpus c = [] {
    Corpus out;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
    out.scene = test::load_gray(test::opencv_data("box_in_scene.png"));
    EXPECT_FALSE(box.empty() || graf.empty() || out.scene.empty()) << "opencv-doc images missing";
    if (box.empty() || graf.empty() || out.scene.empty()) return out;
    out.box = build_index(box, "box");
    out.graf = build_index(graf(cv::Rect(250, 200, 200, 200)).clone(), "graf-crop");
    return out;
  }();
  return c;
}

// What happened to the mutants of one test.
struct Tally {
  long tried = 0;
  long rejected = 0;
  long rejected_checksum = 0;  // of which the message names a checksum
  long loaded = 0;             // loaded, then detect() ran
  long detect_errors = 0;      // of which detect() returned an error Status

  void print(const char* what) const {
    std::printf(
        "%s: %ld mutants tried: %ld rejected (%ld by a checksum, %ld by another check), "
        "%ld loaded and detected (%ld with a detect() error status)\n",
        what, tried, rejected, rejected_checksum, rejected - rejected_checksum, loaded,
        detect_errors);
    std::fflush(stdout);
  }
};

// Loads one mutant; if it loads, reads every model and runs detection.
// Returns the number of detections, or -1 when the mutant was rejected.
int try_mutant(const Bytes& mutant, Tally& tally) {
  ++tally.tried;
  AlignedCopy buffer(mutant);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  if (!s.is_ok()) {
    ++tally.rejected;
    EXPECT_FALSE(s.message().empty()) << "rejected without a message";
    if (s.message().find("checksum") != std::string::npos) ++tally.rejected_checksum;
    return -1;
  }
  ++tally.loaded;
  std::size_t name_bytes = 0;
  for (int i = 0; i < index.model_count(); ++i) {
    const ModelInfo m = index.model(i);
    for (char ch : m.name) name_bytes += static_cast<unsigned char>(ch) != 0 ? 1 : 0;
    EXPECT_LE(std::uint64_t{m.keypoint_begin} + m.keypoint_count, index.keypoint_count());
  }
  EXPECT_LE(name_bytes, mutant.size());
  // Every appearance pixel is read (ASan reports a read past the buffer).
  std::size_t appearance_bytes = 0;
  for (int i = 0; i < index.model_count(); ++i) {
    const ModelAppearance a = index.appearance(i);
    const std::size_t n = static_cast<std::size_t>(a.width) * static_cast<std::size_t>(a.height);
    EXPECT_LE(n, static_cast<std::size_t>(index.max_appearance_pixels()));
    for (std::size_t k = 0; k < n; ++k) appearance_bytes += a.pixels[k] != 0 ? 1 : 0;
  }
  EXPECT_LE(appearance_bytes, mutant.size());
  const cv::Mat& scene = corpus().scene;
  Detector detector(index);
  DetectionList found;
  if (!detector.detect(test::view(scene), found).is_ok()) ++tally.detect_errors;
  for (const Detection& d : found) {
    EXPECT_GE(d.model_id, 0);
    EXPECT_LT(d.model_id, index.model_count());
  }
  return static_cast<int>(found.size());
}

// Positions to damage in a file of `size` bytes: every position below
// `dense`, then `sparse` more drawn at random over the whole file.
std::vector<std::size_t> positions(std::size_t size, std::size_t dense, std::size_t sparse,
                                   std::mt19937_64& rng) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < std::min(dense, size); ++i) out.push_back(i);
  std::uniform_int_distribution<std::size_t> any(0, size - 1);
  for (std::size_t i = 0; i < sparse; ++i) out.push_back(any(rng));
  return out;
}

class IndexMutation : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_FALSE(corpus().box.empty());
    ASSERT_FALSE(corpus().graf.empty());
  }
};

// The undamaged indexes load and detect (the box is in box_in_scene): the
// control for everything below.
TEST_F(IndexMutation, UndamagedIndexesLoadAndDetect) {
  Tally tally;
  EXPECT_GE(try_mutant(corpus().box, tally), 1) << "box not found in box_in_scene.png";
  EXPECT_GE(try_mutant(corpus().graf, tally), 0);
  tally.print("undamaged");
  EXPECT_EQ(tally.loaded, 2);
  EXPECT_EQ(tally.detect_errors, 0);
}

// Every length below 2048 bytes, 600 random lengths beyond, the last 64,
// and the file extended by 1..64 bytes (zeros) and by a copy of itself.
TEST_F(IndexMutation, TruncatedAndExtended) {
  std::mt19937_64 rng(1);
  Tally tally;
  long planned = 0;
  for (const Bytes* original : {&corpus().box, &corpus().graf}) {
    const std::size_t size = original->size();
    std::vector<std::size_t> lengths = positions(size, 2048, 600, rng);
    for (std::size_t i = 1; i <= 64 && i <= size; ++i) lengths.push_back(size - i);
    for (std::size_t length : lengths) {
      const long loaded = tally.loaded;
      try_mutant(Bytes(original->begin(), original->begin() + static_cast<std::ptrdiff_t>(length)),
                 tally);
      EXPECT_EQ(tally.loaded, loaded)
          << "truncated to " << length << " of " << size << " bytes, it loaded";
    }
    for (std::size_t extra = 1; extra <= 64; ++extra) {
      Bytes longer = *original;
      longer.resize(size + extra, 0);
      try_mutant(longer, tally);
    }
    Bytes twice = *original;
    twice.insert(twice.end(), original->begin(), original->end());
    try_mutant(twice, tally);
    planned += static_cast<long>(lengths.size()) + 64 + 1;
  }
  tally.print("truncated/extended");
  EXPECT_EQ(tally.tried, planned);
  EXPECT_GE(tally.tried, 5000);
}

// Single bit flips: every bit of the first 512 bytes, then 500 random bits;
// then 200 random runs of 1..16 bytes set to 0x00, 0xFF or random bytes.
TEST_F(IndexMutation, BitFlipsAndOverwrites) {
  std::mt19937_64 rng(2);
  Tally tally;
  long planned = 0;
  for (const Bytes* original : {&corpus().box, &corpus().graf}) {
    const std::size_t size = original->size();
    std::vector<std::size_t> bits;
    for (std::size_t bit = 0; bit < std::min<std::size_t>(512, size) * 8; ++bit)
      bits.push_back(bit);
    std::uniform_int_distribution<std::size_t> any_bit(0, size * 8 - 1);
    for (int i = 0; i < 500; ++i) bits.push_back(any_bit(rng));
    Bytes mutant = *original;
    for (std::size_t bit : bits) {
      mutant[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
      try_mutant(mutant, tally);
      mutant[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
    std::uniform_int_distribution<std::size_t> any_byte(0, size - 1);
    std::uniform_int_distribution<int> run_length(1, 16), fill(0, 2), byte(0, 255);
    for (int i = 0; i < 200; ++i) {
      mutant = *original;
      const std::size_t at = any_byte(rng);
      const std::size_t end = std::min(size, at + static_cast<std::size_t>(run_length(rng)));
      const int how = fill(rng);
      for (std::size_t j = at; j < end; ++j)
        mutant[j] = how == 0 ? 0x00 : how == 1 ? 0xFF : static_cast<std::uint8_t>(byte(rng));
      try_mutant(mutant, tally);
    }
    planned += static_cast<long>(bits.size()) + 200;
  }
  tally.print("bit flips/overwrites");
  EXPECT_EQ(tally.tried, planned);
  EXPECT_GE(tally.tried, 9000);
}

// Chunks of one real index written into the other (box into graf-crop and
// graf-crop into box): same-length overwrites at random or 64-byte aligned
// positions, chunks inserted or replacing a range of another length, and
// crossovers (a prefix of one, the rest of the other).
TEST_F(IndexMutation, Splices) {
  std::mt19937_64 rng(3);
  Tally tally;
  long planned = 0;
  const Bytes* pairs[2][2] = {{&corpus().graf, &corpus().box}, {&corpus().box, &corpus().graf}};
  for (const auto& pair : pairs) {
    const Bytes& into = *pair[0];
    const Bytes& from = *pair[1];
    std::uniform_int_distribution<std::size_t> at_into(0, into.size() - 1);
    std::uniform_int_distribution<std::size_t> at_from(0, from.size() - 1);
    std::uniform_int_distribution<std::size_t> small(1, 64), large(65, 8192);
    auto chunk_length = [&] { return rng() % 4 == 0 ? large(rng) : small(rng); };
    for (int i = 0; i < 600; ++i) {  // same-length overwrite
      Bytes mutant = into;
      std::size_t dst = at_into(rng), src = at_from(rng);
      if (i % 2 == 1) dst -= dst % 64, src -= src % 64;  // aligned, like sections are
      const std::size_t n = std::min({chunk_length(), into.size() - dst, from.size() - src});
      std::copy_n(from.begin() + static_cast<std::ptrdiff_t>(src), n,
                  mutant.begin() + static_cast<std::ptrdiff_t>(dst));
      try_mutant(mutant, tally);
    }
    for (int i = 0; i < 300; ++i) {  // replace [dst, dst + cut) by a chunk of another length
      const std::size_t dst = at_into(rng), src = at_from(rng);
      const std::size_t cut = std::min(chunk_length() - 1, into.size() - dst);
      const std::size_t n = std::min(chunk_length(), from.size() - src);
      Bytes mutant(into.begin(), into.begin() + static_cast<std::ptrdiff_t>(dst));
      mutant.insert(mutant.end(), from.begin() + static_cast<std::ptrdiff_t>(src),
                    from.begin() + static_cast<std::ptrdiff_t>(src + n));
      mutant.insert(mutant.end(), into.begin() + static_cast<std::ptrdiff_t>(dst + cut),
                    into.end());
      try_mutant(mutant, tally);
    }
    for (int i = 0; i < 100; ++i) {  // crossover at the same offset, aligned or not
      std::size_t k = std::min(at_into(rng), from.size());
      if (i % 2 == 1) k -= k % 64;
      Bytes mutant(into.begin(), into.begin() + static_cast<std::ptrdiff_t>(k));
      mutant.insert(mutant.end(), from.begin() + static_cast<std::ptrdiff_t>(k), from.end());
      try_mutant(mutant, tally);
    }
    planned += 600 + 300 + 100;
  }
  tally.print("splices");
  EXPECT_EQ(tally.tried, planned);
  EXPECT_GE(tally.tried, 2000);
}

}  // namespace
}  // namespace kg
