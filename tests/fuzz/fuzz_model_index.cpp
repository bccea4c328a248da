// libFuzzer target for the model index reader: each input is a candidate
// .kgi file. It is copied into a 64-byte aligned buffer of exactly its size
// (so AddressSanitizer sees any read past its end) and given to
// ModelIndex::view; when it loads, every model record is read, the stored
// keypoint ids are checked against their bounds, and a Detector runs on a
// small synthetic frame -- with the built-in keypoints and with keypoints
// (and vertex descriptors) from the caller -- so whatever the reader accepts
// is also exercised by detection.
//
// Checksums: blind mutations of a checksummed file are nearly all rejected
// at the first CRC, which would leave the checks behind it unfuzzed. So the
// custom mutator below repairs what a mutation broke -- the header's file
// size field, every section CRC the table points to, then the header CRC
// (layout: core/index/index_format.h, docs/FORMAT.md) -- for 7 mutations in 8; the
// eighth stays as mutated, to fuzz the checksum checks themselves.
//
// At exit it prints how the inputs fared; .ci/run fails when most stopped at
// a checksum (the repair would then no longer match the format).
//
//   cmake --preset fuzz && cmake --build --preset fuzz
//   build/fuzz/tests/fuzz/fuzz_model_index CORPUS_DIR SEED_DIR -max_total_time=60
//   KG_FUZZ_READER_ONLY=1 build/fuzz/tests/fuzz/fuzz_model_index ... (no detection)
// Long campaigns of the reader: seeds of 48x48 crops (3 to 7 KB, e.g.
// `keygraph build --roi 120,80,48,48 box.png` in each structure and
// encoding) and -max_len=8192 run about 8 000 inputs a second here; 10 M
// took 20 minutes at format 6.0 (no finding).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"

namespace {

constexpr int kWidth = 160, kHeight = 120;
constexpr std::size_t kAlignment = 64;

// A synthetic 160x120 frame: a shaded background, dark and bright blobs
// and two rectangles (keypoints for the Hessian detector, edges for arc
// profiles), plus the blob centres as caller keypoints and a pseudo-random
// 128-byte vertex descriptor for each.
struct Scene {
  std::vector<std::uint8_t> pixels;
  std::vector<kg::Keypoint> keypoints;
  std::vector<std::uint8_t> vertex_descriptors;
};

Scene make_scene() {
  Scene s;
  s.pixels.resize(static_cast<std::size_t>(kWidth) * kHeight);
  std::uint32_t lcg = 12345;
  auto next = [&lcg] { return lcg = lcg * 1664525u + 1013904223u; };
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x)
      s.pixels[static_cast<std::size_t>(y * kWidth + x)] =
          static_cast<std::uint8_t>(90 + (x + 2 * y) / 8);
  }
  auto fill_rect = [&s](int x0, int y0, int w, int h, std::uint8_t v) {
    for (int y = y0; y < y0 + h; ++y)
      for (int x = x0; x < x0 + w; ++x) s.pixels[static_cast<std::size_t>(y * kWidth + x)] = v;
  };
  fill_rect(20, 15, 50, 30, 200);
  fill_rect(95, 60, 45, 40, 30);
  for (int i = 0; i < 40; ++i) {
    const int cx = 6 + static_cast<int>(next() >> 8) % (kWidth - 12);
    const int cy = 6 + static_cast<int>(next() >> 8) % (kHeight - 12);
    const int r = 2 + static_cast<int>(next() >> 8) % 4;
    const std::uint8_t v = (i % 2 == 0) ? 10 : 245;
    for (int y = cy - r; y <= cy + r; ++y)
      for (int x = cx - r; x <= cx + r; ++x)
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r)
          s.pixels[static_cast<std::size_t>(y * kWidth + x)] = v;
    s.keypoints.push_back({static_cast<float>(cx), static_cast<float>(cy),
                           static_cast<float>(r) / 1.4142f, static_cast<float>(40 - i)});
  }
  s.vertex_descriptors.resize(s.keypoints.size() * kg::kVertexDescriptorSize);
  for (auto& b : s.vertex_descriptors) b = static_cast<std::uint8_t>(next() >> 24);
  return s;
}

const Scene& scene() {
  static const Scene s = make_scene();
  return s;
}

// How the inputs fared (printed at exit).
struct Counts {
  unsigned long inputs = 0, rejected = 0, rejected_checksum = 0, loaded = 0, detections = 0;
  unsigned long name_bytes = 0;  // sum of the model names' bytes (keeps the reads)
};
Counts counts;

// KG_FUZZ_READER_ONLY=1: the reader and the record checks only, no
// detection: about 100 times the executions per second, for long campaigns
// of the reader itself (detection costs a workspace per input).
bool reader_only = false;

void print_counts() {
  std::fprintf(stderr,
               "fuzz_model_index: %lu inputs: %lu rejected (%lu at a checksum), %lu loaded and "
               "%s (%lu detections; name checksum %lu)\n",
               counts.inputs, counts.rejected, counts.rejected_checksum, counts.loaded,
               reader_only ? "checked, no detection (KG_FUZZ_READER_ONLY)" : "detected",
               counts.detections, counts.name_bytes);
}

// Stops the run (libFuzzer reports the input) when a loaded index breaks a
// guarantee of the reader.
void require(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_model_index: loaded index breaks a reader guarantee: %s\n", what);
    std::abort();
  }
}

void exercise(const kg::ModelIndex& index) {
  const std::uint64_t keypoints = index.keypoint_count();
  unsigned long name_bytes = 0;
  for (int i = 0; i < index.model_count(); ++i) {
    const kg::ModelInfo m = index.model(i);
    for (char c : m.name) name_bytes += static_cast<unsigned char>(c);
    require(std::uint64_t{m.keypoint_begin} + m.keypoint_count <= keypoints,
            "model keypoint range out of bounds");
  }
  for (std::uint32_t i = 0; i < index.arc_count(); ++i) {
    const kg::ModelArc arc = index.arc(i);
    require(arc.from < keypoints && arc.to < keypoints, "arc keypoint id out of bounds");
  }
  // The quality report (format 6.1): what inspect reads of it is in range.
  if (index.has_quality()) {
    for (int i = 0; i < index.model_count(); ++i) {
      const kg::ModelQuality q = index.model_quality(i);
      require(std::uint64_t{q.view_begin} + q.view_count <= index.view_quality_count(),
              "quality view range out of bounds");
      require(q.shared_arcs <= index.model(i).arc_count, "more shared arcs than arcs");
      for (std::uint32_t v = q.view_begin; v < q.view_begin + q.view_count; ++v)
        name_bytes += index.view_quality(v).keypoints & 1u;
    }
    for (std::uint32_t i = 0; i < index.look_alike_count(); ++i) {
      const kg::LookAlike p = index.look_alike(i);
      require(p.shown < static_cast<std::uint32_t>(index.model_count()) &&
                  p.detected < static_cast<std::uint32_t>(index.model_count()),
              "look-alike model id out of bounds");
    }
  }
  // The appearances (format 6.2): sizes as documented, every pixel inside
  // the index (each one read, for ASan).
  if (index.has_appearance()) {
    const std::uint8_t* begin = index.data();
    const std::uint8_t* end = begin + index.byte_size();
    const int limit = index.params().views.appearance_size;
    for (int i = 0; i < index.model_count(); ++i) {
      const kg::ModelAppearance a = index.appearance(i);
      require(!a.empty() && a.width >= 1 && a.height >= 1 && a.width <= limit &&
                  a.height <= limit && a.scale > 0.f && a.scale <= 1.f,
              "appearance size or scale out of range");
      const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
      require(pixels <= static_cast<std::size_t>(index.max_appearance_pixels()),
              "appearance larger than max_appearance_pixels()");
      require(a.pixels >= begin && pixels <= static_cast<std::size_t>(end - a.pixels),
              "appearance pixels outside the index");
      for (std::size_t k = 0; k < pixels; ++k) name_bytes += a.pixels[k] & 1u;
    }
  } else {
    require(index.max_appearance_pixels() == 0 && index.appearance(0).empty(),
            "appearance without has_appearance()");
  }
  counts.name_bytes += name_bytes;
  if (reader_only) return;

  const Scene& s = scene();
  const kg::ImageView frame(s.pixels.data(), kWidth, kHeight);
  kg::Limits limits;  // small, so that an execution stays fast
  limits.max_keypoints = 400;
  limits.max_scene_keypoints = 200;
  limits.max_arc_matches = 256;
  limits.max_correspondences = 4096;
  limits.max_detections = 4;
  kg::Detector detector(index, limits);
  kg::DetectionList found;
  // The built-in keypoints (an error Status for indexes that need the
  // caller's, which is fine), then the caller's keypoints and descriptors.
  (void)detector.detect(frame, found);
  counts.detections += found.size();
  (void)detector.detect(frame, s.keypoints.data(), static_cast<int>(s.keypoints.size()),
                        s.vertex_descriptors.data(), found);
  counts.detections += found.size();
  for (const kg::Detection& d : found) {
    require(d.model_id >= 0 && d.model_id < index.model_count(), "detection model id");
  }
}

// Makes a mutated file consistent again where it can: file size field,
// section CRCs, header CRC. Reads only within [data, data + size).
void repair_checksums(std::uint8_t* d, std::size_t size) {
  using namespace kg::format;
  if (size < kHeaderSize) return;
  store<std::uint64_t>(d + kOffFileSize, size);
  const auto table_offset = load<std::uint32_t>(d + kOffTableOffset);
  const auto section_count = load<std::uint32_t>(d + kOffSectionCount);
  if (section_count > 64) return;
  const std::uint64_t table_end =
      std::uint64_t{table_offset} + std::uint64_t{section_count} * kSectionEntrySize;
  if (table_end > size || table_end < kHeaderSize) return;
  for (std::uint32_t i = 0; i < section_count; ++i) {
    std::uint8_t* e = d + table_offset + std::size_t{i} * kSectionEntrySize;
    const auto offset = load<std::uint64_t>(e + kEntOffset);
    const auto length = load<std::uint64_t>(e + kEntSize);
    if (offset > size || length > size - offset) continue;
    store<std::uint32_t>(e + kEntCrc, kg::crc32(d + offset, static_cast<std::size_t>(length)));
  }
  const std::uint8_t zero[4] = {0, 0, 0, 0};
  std::uint32_t crc = kg::crc32(d, kOffHeaderCrc);
  crc = kg::crc32(zero, 4, crc);
  crc = kg::crc32(d + kOffHeaderCrc + 4, static_cast<std::size_t>(table_end) - kOffHeaderCrc - 4,
                  crc);
  store<std::uint32_t>(d + kOffHeaderCrc, crc);
}

}  // namespace

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::atexit(print_counts);
  const char* only = std::getenv("KG_FUZZ_READER_ONLY");
  reader_only = only != nullptr && std::strcmp(only, "1") == 0;
  if (!reader_only) (void)scene();
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int seed) {
  size = LLVMFuzzerMutate(data, size, max_size);
  if (seed % 8 != 0) repair_checksums(data, size);
  return size;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ++counts.inputs;
  auto* buffer = static_cast<std::uint8_t*>(
      ::operator new[](size > 0 ? size : 1, std::align_val_t(kAlignment)));
  if (size > 0) std::memcpy(buffer, data, size);
  {
    kg::ModelIndex index;
    const kg::Status s = kg::ModelIndex::view(buffer, size, index);
    if (s.is_ok()) {
      ++counts.loaded;
      exercise(index);
    } else {
      ++counts.rejected;
      if (s.message().find("checksum") != std::string::npos) ++counts.rejected_checksum;
    }
  }
  ::operator delete[](buffer, std::align_val_t(kAlignment));
  return 0;
}
