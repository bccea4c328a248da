// The .kgi model index (format 2.0): writer/reader round trip on real models
// in each descriptor encoding, byte-exact determinism, golden files, atomic
// file writes, mapping, allocation-free views, and the reader's validation:
// every kind of damage is an error Status that names the problem, never a
// crash.
#include "keygraph/model_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/in_memory_index.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "builder/model_quality.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "core/index/index_internals.h"
#include "core/index/kdtree.h"
#include "core/keygraphs/keygraph.h"
#include "core/pose/homography.h"
#include "core/selection/selection.h"
#include "support/alloc_counter.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace kg {
namespace {

using test::TempDir;

using Bytes = std::vector<std::uint8_t>;
using format::load;
using format::store;

// A copy of an index in a buffer of exactly its size (so ASan sees any
// read past the end), 64-byte aligned plus `shift`.
class AlignedBytes {
 public:
  explicit AlignedBytes(const Bytes& bytes, std::size_t shift = 0) : size_(bytes.size()) {
    base_ = static_cast<std::uint8_t*>(
        ::operator new[](size_ + shift + 1, std::align_val_t(format::kAlignment)));
    data_ = base_ + shift;
    if (size_ > 0) std::memcpy(data_, bytes.data(), size_);
  }
  ~AlignedBytes() { ::operator delete[](base_, std::align_val_t(format::kAlignment)); }
  AlignedBytes(const AlignedBytes&) = delete;
  AlignedBytes& operator=(const AlignedBytes&) = delete;
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  std::uint8_t* base_ = nullptr;
  std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

Status try_view(const Bytes& bytes) {
  AlignedBytes buffer(bytes);
  ModelIndex index;
  return ModelIndex::view(buffer.data(), buffer.size(), index);
}

// Fails unless `bytes` is rejected with `code` and a message containing `needle`.
::testing::AssertionResult rejected(const Bytes& bytes, std::string_view needle,
                                    StatusCode code = StatusCode::kCorruptData) {
  const Status s = try_view(bytes);
  if (s.is_ok()) return ::testing::AssertionFailure() << "loaded; expected '" << needle << "'";
  if (s.code() != code)
    return ::testing::AssertionFailure()
           << "code " << static_cast<int>(s.code()) << " (" << s.message() << ")";
  if (s.message().find(needle) == std::string::npos)
    return ::testing::AssertionFailure()
           << "message '" << s.message() << "' lacks '" << needle << "'";
  return ::testing::AssertionSuccess() << s.message();
}

// --- Section table access on a serialized index --------------------------

std::size_t table_offset(const Bytes& b) {
  return load<std::uint32_t>(b.data() + format::kOffTableOffset);
}
std::size_t section_count(const Bytes& b) {
  return load<std::uint32_t>(b.data() + format::kOffSectionCount);
}
std::size_t table_end(const Bytes& b) {
  return table_offset(b) + section_count(b) * format::kSectionEntrySize;
}

// Byte offset of the table entry for section `id`.
std::size_t entry(const Bytes& b, std::uint32_t id) {
  for (std::size_t i = 0; i < section_count(b); ++i) {
    const std::size_t e = table_offset(b) + i * format::kSectionEntrySize;
    if (load<std::uint32_t>(b.data() + e + format::kEntId) == id) return e;
  }
  ADD_FAILURE() << "section " << id << " not in the table";
  return table_offset(b);
}
std::size_t section_offset(const Bytes& b, std::uint32_t id) {
  return static_cast<std::size_t>(
      load<std::uint64_t>(b.data() + entry(b, id) + format::kEntOffset));
}
std::size_t section_size(const Bytes& b, std::uint32_t id) {
  return static_cast<std::size_t>(load<std::uint64_t>(b.data() + entry(b, id) + format::kEntSize));
}

// Recomputes the header CRC the way the format defines it: CRC-32 of
// [0, table end) with the CRC field zeroed.
void fix_header_crc(Bytes& b) {
  store<std::uint32_t>(b.data() + format::kOffHeaderCrc, 0);
  store<std::uint32_t>(b.data() + format::kOffHeaderCrc, crc32(b.data(), table_end(b)));
}

// Recomputes every section CRC, then the header CRC: after this only the
// semantic checks can reject the file.
void reseal(Bytes& b) {
  for (std::uint32_t id = 1; id <= format::kLastSectionId; ++id) {
    const std::size_t e = entry(b, id);
    store<std::uint32_t>(b.data() + e + format::kEntCrc,
                         crc32(b.data() + section_offset(b, id), section_size(b, id)));
  }
  fix_header_crc(b);
}

// --- Real models, built once ----------------------------------------------

constexpr DescriptorEncoding kEncodings[] = {DescriptorEncoding::kFloat32,
                                             DescriptorEncoding::kInt16, DescriptorEncoding::kInt8};

// The paper's single model image (no views): the format tests compare arcs
// with the keypoints' own scales, one arc per keypoint pair.
Params paper_params() {
  Params p;
  p.views.min_size = 0.f;
  p.graph.max_neighbour_rank = 0;  // every pair in range, as the paper's model graph
  return p;
}

Params with_encoding(DescriptorEncoding e, Params p = paper_params()) {
  p.descriptor.encoding = e;
  return p;
}

// What the format tests share, built once per process and only by the
// tests that use it (ctest runs each test in a process of its own, 43 of
// them ModelIndexTest's): the two models and their index in every test,
// the index in each encoding and the small corpus where a test asks for
// them.
struct Corpus {
  std::string error;
  Params params = paper_params();
  std::vector<BuiltModel> models;  // box.png, a 200x200 crop of graf1.png
  Bytes bytes;                     // serialize_index(models, params): the default encoding
};
struct EncodedCorpus {
  std::string error;
  Bytes encoded[3];  // corpus()'s models in each encoding (index: DescriptorEncoding)
};
// Two small crops (box.png, graf1.png) with their measured quality
// report: for the bit-flip sweep.
struct SmallCorpus {
  std::string error;
  Bytes small;
  Bytes small_encoded[3];  // the same in each encoding
  QualityReport small_quality;
  std::vector<BuiltModel> small_models;
};

std::string build(const cv::Mat& gray, const std::string& name, BuiltModel& out) {
  if (gray.empty()) return name + ": image missing (install opencv-doc)";
  const Status s = build_model(gray, name, paper_params(), out);
  return s ? std::string() : s.message();
}

const Corpus& corpus() {
  static const Corpus c = [] {
    Corpus k;
    k.models.resize(2);
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
    k.error = build(box, "box", k.models[0]);
    if (k.error.empty() && !graf.empty())
      k.error = build(graf(cv::Rect(300, 220, 200, 200)).clone(), "graf1_crop", k.models[1]);
    if (k.error.empty() && graf.empty()) k.error = "graf1.png missing (install opencv-doc)";
    if (k.error.empty()) {
      const Status s = serialize_index(k.models, k.params, k.bytes);
      if (!s) k.error = s.message();
    }
    return k;
  }();
  return c;
}

const EncodedCorpus& encoded_corpus() {
  static const EncodedCorpus c = [] {
    EncodedCorpus k;
    k.error = corpus().error;
    for (DescriptorEncoding e : kEncodings) {
      if (!k.error.empty()) break;
      const Status s =
          serialize_index(corpus().models, with_encoding(e), k.encoded[static_cast<int>(e)]);
      if (!s) k.error = s.message();
    }
    return k;
  }();
  EXPECT_TRUE(c.error.empty()) << c.error;
  return c;
}

const SmallCorpus& small_corpus() {
  static const SmallCorpus c = [] {
    SmallCorpus k;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
    if (box.empty() || graf.empty()) k.error = "box.png or graf1.png missing (install opencv-doc)";
    const Params params = paper_params();
    // Small enough that thousands of full validations stay fast under ASan.
    std::vector<BuiltModel> small(2);
    if (k.error.empty())
      k.error = build(box(cv::Rect(100, 50, 96, 96)).clone(), "box_crop", small[0]);
    if (k.error.empty())
      k.error = build(graf(cv::Rect(350, 250, 80, 80)).clone(), "graf1_small", small[1]);
    if (k.error.empty()) {
      const std::vector<cv::Mat> grays = {box(cv::Rect(100, 50, 96, 96)).clone(),
                                          graf(cv::Rect(350, 250, 80, 80)).clone()};
      k.small_models = small;
      Status s = measure_quality(small, grays, params, QualityOptions{}, k.small_quality);
      if (s) s = serialize_index(small, params, k.small, &k.small_quality);
      if (!s) k.error = s.message();
    }
    for (DescriptorEncoding e : kEncodings) {
      if (!k.error.empty()) break;
      const Status s = serialize_index(small, with_encoding(e),
                                       k.small_encoded[static_cast<int>(e)], &k.small_quality);
      if (!s) k.error = s.message();
    }
    return k;
  }();
  EXPECT_TRUE(c.error.empty()) << c.error;
  return c;
}

class ModelIndexTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(corpus().error.empty()) << corpus().error;
    ASSERT_GT(corpus().models[0].arcs.size(), 0u);
    ASSERT_GT(corpus().models[1].arcs.size(), 0u);
  }
  const std::vector<BuiltModel>& models() const { return corpus().models; }
  const Bytes& bytes() const { return corpus().bytes; }
  const Bytes& encoded(DescriptorEncoding e) const {
    return encoded_corpus().encoded[static_cast<int>(e)];
  }
};

// Writes `p`'s parameter block over the index's (serialize_params does not
// validate, so it can encode bad values) and fixes the header CRC.
void put_params(Bytes& b, const Params& p) {
  format::serialize_params(p, b.data() + load<std::uint32_t>(b.data() + format::kOffParamsOffset));
  fix_header_crc(b);
}

void expect_same_params(const Params& got, const Params& want) {
  std::uint8_t a[format::kParamsSize], b[format::kParamsSize];
  format::serialize_params(got, a);
  format::serialize_params(want, b);
  EXPECT_EQ(0, std::memcmp(a, b, sizeof(a))) << "serialized parameter blocks differ";
  EXPECT_EQ(got.keypoints.detector, want.keypoints.detector);
  EXPECT_EQ(got.keypoints.hessian_threshold, want.keypoints.hessian_threshold);
  EXPECT_EQ(got.keypoints.model_scales, want.keypoints.model_scales);
  EXPECT_EQ(got.graph.structure, want.graph.structure);
  EXPECT_EQ(got.graph.scene_sampling, want.graph.scene_sampling);
  EXPECT_EQ(got.graph.min_distance, want.graph.min_distance);
  EXPECT_EQ(got.graph.max_distance, want.graph.max_distance);
  EXPECT_EQ(got.graph.max_anisotropy, want.graph.max_anisotropy);
  EXPECT_EQ(got.descriptor.blur_sigma, want.descriptor.blur_sigma);
  EXPECT_EQ(got.descriptor.profile_length, want.descriptor.profile_length);
  EXPECT_EQ(got.descriptor.coefficients, want.descriptor.coefficients);
  EXPECT_EQ(got.descriptor.similarity_threshold, want.descriptor.similarity_threshold);
  EXPECT_EQ(got.descriptor.encoding, want.descriptor.encoding);
  EXPECT_EQ(got.ransac.confidence, want.ransac.confidence);
  EXPECT_EQ(got.ransac.max_iterations, want.ransac.max_iterations);
  EXPECT_EQ(got.ransac.inlier_threshold, want.ransac.inlier_threshold);
  EXPECT_EQ(got.ransac.max_instances, want.ransac.max_instances);
  EXPECT_EQ(got.ransac.seed, want.ransac.seed);
  EXPECT_EQ(got.ransac.min_appearance, want.ransac.min_appearance);
  EXPECT_EQ(got.views.appearance_size, want.views.appearance_size);
}

// The descriptor components of a tree point.
template <class T, std::size_t N>
std::array<T, kDescriptorSize> descriptor_part(const std::array<T, N>& p) {
  std::array<T, kDescriptorSize> d{};
  std::copy(p.begin(), p.begin() + kDescriptorSize, d.begin());
  return d;
}

// Whether tree slot `slot` holds descriptor d with the attributes of the
// arc from keypoint a to b (scales sa, sb), encoded as the index stores them.
bool slot_holds(const ModelIndex& index, std::uint32_t slot, const ArcDescriptor& d, Point2f a,
                Point2f b, float sa, float sb) {
  float attributes[kArcAttributes];
  arc_attributes(a, b, sa, sb, attributes);
  const ArcSearchPoint p = search_point(d, attributes);
  switch (index.descriptor_encoding()) {
    case DescriptorEncoding::kFloat32:
      return IndexInternals::tree_points_f32(index)[slot] == p;
    case DescriptorEncoding::kInt16:
      return IndexInternals::tree_points_i16(index)[slot] == encode_point<std::int16_t>(p);
    case DescriptorEncoding::kInt8:
      return IndexInternals::tree_points_i8(index)[slot] == encode_point<std::int8_t>(p);
  }
  return false;
}

// Checks everything the reader exposes against the builder's data.
void expect_matches(const ModelIndex& index, const std::vector<BuiltModel>& models) {
  ASSERT_EQ(index.model_count(), static_cast<int>(models.size()));
  EXPECT_FALSE(index.empty());
  EXPECT_EQ(index.version_major(), format::kVersionMajor);
  EXPECT_EQ(index.version_minor(), format::kVersionMinor);
  std::uint32_t kp_begin = 0, arcs = 0;
  // (from, to) in global keypoint ids -> the builder's descriptor.
  std::map<std::pair<std::uint32_t, std::uint32_t>, ArcDescriptor> built;
  for (int m = 0; m < index.model_count(); ++m) {
    SCOPED_TRACE("model " + std::to_string(m));
    const BuiltModel& bm = models[static_cast<std::size_t>(m)];
    const ModelInfo info = index.model(m);
    EXPECT_EQ(info.name, bm.name);
    EXPECT_EQ(info.width, static_cast<float>(bm.width));
    EXPECT_EQ(info.height, static_cast<float>(bm.height));
    EXPECT_EQ(info.keypoint_begin, kp_begin);
    EXPECT_EQ(info.keypoint_count, bm.keypoints.size());
    EXPECT_EQ(info.arc_count, bm.arcs.size());
    EXPECT_EQ(info.keygraph_count, bm.keygraphs);
    // Outline: the image rectangle through corner pixel centres, clockwise.
    const float w = static_cast<float>(bm.width - 1), h = static_cast<float>(bm.height - 1);
    const Point2f outline[4] = {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
    for (int c = 0; c < 4; ++c) {
      EXPECT_EQ(info.outline[c].x, outline[c].x);
      EXPECT_EQ(info.outline[c].y, outline[c].y);
    }
    for (std::size_t i = 0; i < bm.keypoints.size(); ++i) {
      const Point2f& p = index.keypoints()[kp_begin + i];
      ASSERT_TRUE(p.x == bm.keypoints[i].x && p.y == bm.keypoints[i].y) << "keypoint " << i;
      ASSERT_EQ(index.keypoint_scales()[kp_begin + i], bm.keypoint_scales[i]) << "keypoint " << i;
    }
    for (std::size_t i = 0; i < bm.arcs.size(); ++i)
      built[{bm.arcs[i].from + kp_begin, bm.arcs[i].to + kp_begin}] = bm.descriptors[i];
    // The appearance, byte for byte, when the parameters store one.
    const ModelAppearance look = index.appearance(m);
    EXPECT_EQ(look.empty(), index.params().views.appearance_size == 0);
    if (!look.empty()) {
      ASSERT_EQ(look.width, bm.appearance.cols);
      ASSERT_EQ(look.height, bm.appearance.rows);
      EXPECT_EQ(look.scale, bm.appearance_scale);
      for (int y = 0; y < look.height; ++y)
        ASSERT_EQ(0, std::memcmp(look.pixels + static_cast<std::size_t>(y) * look.width,
                                 bm.appearance.ptr<std::uint8_t>(y), look.width))
            << "appearance row " << y;
    }
    // Owner lookups at both ends of each range (and the middle).
    if (info.keypoint_count > 0) {
      EXPECT_EQ(index.model_of_keypoint(kp_begin), m);
      EXPECT_EQ(index.model_of_keypoint(kp_begin + info.keypoint_count / 2), m);
      EXPECT_EQ(index.model_of_keypoint(kp_begin + info.keypoint_count - 1), m);
    }
    kp_begin += info.keypoint_count;
    arcs += info.arc_count;
  }
  EXPECT_EQ(index.keypoint_count(), kp_begin);
  EXPECT_EQ(index.arc_count(), arcs);
  EXPECT_EQ(index.model(-1).name, "");
  EXPECT_EQ(index.model(index.model_count()).name, "");

  // Tree arcs: every built arc exactly once, in some slot whose descriptor
  // is that arc's (encoded); both ends in one model.
  ASSERT_EQ(built.size(), index.arc_count()) << "duplicate arcs in the builder's models";
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> seen;
  std::vector<std::uint32_t> per_model(models.size(), 0);
  for (std::uint32_t slot = 0; slot < index.arc_count(); ++slot) {
    const ModelArc a = index.arc(slot);
    const auto it = built.find({a.from, a.to});
    ASSERT_TRUE(it != built.end()) << "slot " << slot << " holds an unknown arc";
    ASSERT_EQ(++seen[it->first], 1) << "slot " << slot << " repeats an arc";
    ASSERT_TRUE(slot_holds(index, slot, it->second, index.keypoints()[a.from],
                           index.keypoints()[a.to], index.keypoint_scales()[a.from],
                           index.keypoint_scales()[a.to]))
        << "slot " << slot;
    const int m = index.model_of_keypoint(a.from);
    ASSERT_EQ(index.model_of_keypoint(a.to), m);
    ++per_model[static_cast<std::size_t>(m)];
  }
  for (int m = 0; m < index.model_count(); ++m)
    EXPECT_EQ(per_model[static_cast<std::size_t>(m)], index.model(m).arc_count);
  EXPECT_EQ(index.tree_depth(), kdtree_depth(index.arc_count()));
  const std::uint32_t nodes = (1u << index.tree_depth()) - 1;
  ASSERT_EQ(index.tree_node_count(), nodes);
  const DescriptorEncoding e = index.descriptor_encoding();
  EXPECT_EQ(IndexInternals::tree_points_f32(index) != nullptr, e == DescriptorEncoding::kFloat32);
  EXPECT_EQ(IndexInternals::tree_points_i16(index) != nullptr, e == DescriptorEncoding::kInt16);
  EXPECT_EQ(IndexInternals::tree_points_i8(index) != nullptr, e == DescriptorEncoding::kInt8);
  EXPECT_EQ(IndexInternals::tree_nodes_f32(index) != nullptr, e == DescriptorEncoding::kFloat32);
  EXPECT_EQ(IndexInternals::tree_nodes_int(index) != nullptr, e != DescriptorEncoding::kFloat32);
  for (std::uint32_t n = 0; n < nodes; ++n) {
    if (e == DescriptorEncoding::kFloat32) {
      ASSERT_LT(IndexInternals::tree_nodes_f32(index)[n].dim,
                static_cast<std::uint32_t>(kSearchDims));
    } else {
      ASSERT_LT(IndexInternals::tree_nodes_int(index)[n].dim,
                static_cast<std::uint32_t>(kSearchDims));
    }
  }
}

TEST_F(ModelIndexTest, RoundTripThroughView) {
  AlignedBytes buffer(bytes());
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(index.byte_size(), bytes().size());
  EXPECT_EQ(bytes().size() % format::kAlignment, 0u);
  expect_matches(index, models());
  expect_same_params(index.params(), paper_params());
  // Zero copy: the accessors point into the caller's buffer.
  EXPECT_GE(reinterpret_cast<const std::uint8_t*>(index.keypoints()), buffer.data());
  EXPECT_LT(reinterpret_cast<const std::uint8_t*>(index.keypoints()),
            buffer.data() + buffer.size());
}

TEST_F(ModelIndexTest, RoundTripInEachEncoding) {
  for (DescriptorEncoding e : kEncodings) {
    SCOPED_TRACE(encoding_name(e));
    const Bytes& b = encoded(e);
    AlignedBytes buffer(b);
    ModelIndex index;
    const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(index.descriptor_encoding(), e);
    expect_matches(index, models());
    expect_same_params(index.params(), with_encoding(e));
    // Section sizes follow the encoding: 32, 16 or 8 bytes per tree point
    // (descriptor and attributes), 8 or 4 per tree node; the arcs are 4 + 2
    // bytes in every encoding.
    EXPECT_EQ(section_size(b, format::kSectionDescriptors),
              std::size_t{index.arc_count()} * encoded_point_size(e));
    EXPECT_EQ(section_size(b, format::kSectionTreeNodes),
              std::size_t{index.tree_node_count()} * format::tree_node_size(e));
    EXPECT_EQ(section_size(b, format::kSectionTreeArcs), std::size_t{index.arc_count()} * 4);
    EXPECT_EQ(section_size(b, format::kSectionTreeArcTargets), std::size_t{index.arc_count()} * 2);
    for (std::uint32_t id : {format::kSectionDescriptors, format::kSectionTreeNodes})
      EXPECT_EQ(load<std::uint32_t>(b.data() + entry(b, id) + format::kEntEncoding),
                static_cast<std::uint32_t>(e));
  }
  // Smaller encodings make smaller files (int8: about 15 bytes per arc).
  EXPECT_LT(encoded(DescriptorEncoding::kInt16).size(),
            encoded(DescriptorEncoding::kFloat32).size());
  EXPECT_LT(encoded(DescriptorEncoding::kInt8).size(), encoded(DescriptorEncoding::kInt16).size());
  const double arcs = static_cast<double>(models()[0].arcs.size() + models()[1].arcs.size());
  EXPECT_LE(static_cast<double>(encoded(DescriptorEncoding::kInt8).size()) / arcs, 16.0);
}

// The search through the index (ArcSearch: quantised query, scaled radius
// and attribute box) finds exactly the slots a brute-force scan of the
// stored points finds in the same domain, in each encoding, with and
// without the scale attributes.
TEST_F(ModelIndexTest, ArcSearchEqualsBruteForceOnStoredDescriptors) {
  for (DescriptorEncoding e : kEncodings) {
    SCOPED_TRACE(encoding_name(e));
    AlignedBytes buffer(encoded(e));
    ModelIndex index;
    ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
    const ArcSearch search(index, 0);  // exact (no leaf limit)
    const std::uint32_t n = index.arc_count();
    const float r = index.params().descriptor.similarity_threshold;
    std::int64_t r2 = 0;
    if (e != DescriptorEncoding::kFloat32) {
      ASSERT_TRUE(scaled_radius2(r, e, std::numeric_limits<std::int64_t>::max(), r2));
    }
    const std::int32_t box = attribute_box(index.params().graph);  // grid steps
    ASSERT_GT(box, 0);
    std::vector<std::uint32_t> out(n);
    std::size_t matches = 0, unboxed_matches = 0;
    // Queries: builder descriptors of every 499th arc of box, slightly
    // moved, with their arc's attributes slightly moved.
    const BuiltModel& m = models()[0];
    for (std::size_t q = 0; q < m.descriptors.size(); q += 499) {
      ArcDescriptor query = m.descriptors[q];
      query[q % kDescriptorSize] += 0.05f;
      const ModelArc arc = m.arcs[q];
      float attributes[kArcAttributes];
      ASSERT_TRUE(arc_attributes(m.keypoints[arc.from], m.keypoints[arc.to],
                                 m.keypoint_scales[arc.from], m.keypoint_scales[arc.to],
                                 attributes));
      attributes[0] += 3.f;  // grid steps
      attributes[1] -= 7.f;
      const ArcSearchPoint p = search_point(query, attributes);
      for (const bool with_box : {true, false}) {
        std::vector<std::uint32_t> expected;
        for (std::uint32_t slot = 0; slot < n; ++slot) {
          bool near = false, inside = true;
          auto in_box = [&](auto stored, auto wanted, auto half_width) {
            for (int i = kDescriptorSize; i < kSearchDims; ++i) {
              const double diff = static_cast<double>(stored[i]) - static_cast<double>(wanted[i]);
              if (std::fabs(diff) > static_cast<double>(half_width)) return false;
            }
            return true;
          };
          switch (e) {
            case DescriptorEncoding::kFloat32:
              near = kd_distance2(IndexInternals::tree_points_f32(index)[slot], p) < r * r;
              inside = in_box(IndexInternals::tree_points_f32(index)[slot], p, box);
              break;
            case DescriptorEncoding::kInt16:
              near = kd_distance2(IndexInternals::tree_points_i16(index)[slot],
                                  encode_point<std::int16_t>(p)) < r2;
              inside = in_box(IndexInternals::tree_points_i16(index)[slot],
                              encode_point<std::int16_t>(p), box);
              break;
            case DescriptorEncoding::kInt8:
              near = kd_distance2(IndexInternals::tree_points_i8(index)[slot],
                                  encode_point<std::int8_t>(p)) < r2;
              inside = in_box(IndexInternals::tree_points_i8(index)[slot],
                              encode_point<std::int8_t>(p), box);
              break;
          }
          if (near && (inside || !with_box)) expected.push_back(slot);
        }
        const std::uint32_t found =
            search.radius_search(query, with_box ? attributes : nullptr, out.data(), n);
        std::vector<std::uint32_t> got(out.begin(), out.begin() + found);
        std::sort(got.begin(), got.end());
        ASSERT_EQ(got, expected) << "query " << q << (with_box ? " with" : " without") << " box";
        (with_box ? matches : unboxed_matches) += found;
      }
    }
    EXPECT_GT(matches, 0u);
    // The box cuts: fewer matches with it than without.
    EXPECT_LT(matches, unboxed_matches);
  }
}

TEST_F(ModelIndexTest, NonDefaultParamsRoundTrip) {
  Params p = paper_params();
  p.keypoints.detector = KeypointDetector::kMser;
  p.graph.structure = Structure::kCircuit4;
  p.graph.scene_sampling = SceneSampling::kStrongest;
  p.graph.min_distance = 12.5f;
  p.graph.max_distance = 80.f;
  p.descriptor.similarity_threshold = 0.25f;
  p.descriptor.profile_length = 40;
  p.descriptor.encoding = DescriptorEncoding::kInt16;
  p.ransac.confidence = 0.995;
  p.ransac.max_iterations = 777;
  p.ransac.inlier_threshold = 3.25;
  p.ransac.max_instances = 7;
  p.ransac.seed = 0x0123456789abcdefULL;
  p.ransac.min_appearance = -0.25f;
  p.views.appearance_size = 0;  // none stored, though the models have one
  p.views.blurred_max_size = 170.f;
  p.views.glow_max_size = 120.f;  // 6.12
  Bytes b;
  ASSERT_TRUE(serialize_index(models(), p, b));
  AlignedBytes buffer(b);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  expect_same_params(index.params(), p);
  EXPECT_FALSE(index.has_appearance());
}

TEST_F(ModelIndexTest, OwnerLookupsOnManyModels) {
  // Five models (some repeated) exercise the binary search beyond two ranges.
  std::vector<BuiltModel> many = {models()[1], models()[0], models()[1], models()[1], models()[0]};
  for (std::size_t i = 0; i < many.size(); ++i)
    many[i].name = std::string("m").append(
        std::to_string(i));  // not "m" + ...: GCC 12 -Wrestrict false positive
  Bytes b;
  ASSERT_TRUE(serialize_index(many, paper_params(), b));
  AlignedBytes buffer(b);
  ModelIndex index;
  ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
  expect_matches(index, many);
  for (std::uint32_t k = 0; k < index.keypoint_count(); ++k) {
    const ModelInfo info = index.model(index.model_of_keypoint(k));
    ASSERT_TRUE(k >= info.keypoint_begin && k < info.keypoint_begin + info.keypoint_count) << k;
  }
}

TEST_F(ModelIndexTest, SerializationIsDeterministic) {
  Bytes again;
  ASSERT_TRUE(serialize_index(models(), paper_params(), again));
  EXPECT_TRUE(again == bytes()) << "two serializations of the same models differ";

  // Building the same image again gives the same model and the same bytes.
  BuiltModel box;
  const cv::Mat image = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(image.empty());
  ASSERT_TRUE(build_model(image, "box", paper_params(), box));
  const BuiltModel& first = models()[0];
  EXPECT_EQ(box.keygraphs, first.keygraphs);
  ASSERT_EQ(box.keypoints.size(), first.keypoints.size());
  ASSERT_EQ(box.arcs.size(), first.arcs.size());
  std::vector<BuiltModel> rebuilt = {box, models()[1]};
  Bytes rebuilt_bytes;
  ASSERT_TRUE(serialize_index(rebuilt, paper_params(), rebuilt_bytes));
  EXPECT_TRUE(rebuilt_bytes == bytes()) << "rebuilding box.png changed the index bytes";
}

TEST_F(ModelIndexTest, SerializeRejectsBadInput) {
  Bytes b;
  EXPECT_FALSE(serialize_index({}, paper_params(), b));
  std::vector<BuiltModel> unnamed = {models()[0]};
  unnamed[0].name.clear();
  EXPECT_FALSE(serialize_index(unnamed, paper_params(), b));
  Params bad;
  bad.graph.structure = static_cast<Structure>(7);
  EXPECT_FALSE(serialize_index(models(), bad, b));
}

// --- Vertex descriptors -----------------------------------------------------

Params sift_params() {
  Params p = paper_params();
  p.descriptor.vertex_descriptor = VertexDescriptor::kSift;
  return p;
}

// The corpus' two images built with SIFT vertex descriptors.
struct SiftCorpus {
  std::string error;
  std::vector<BuiltModel> models;
  Bytes bytes;
};

const SiftCorpus& sift_corpus() {
  static const SiftCorpus c = [] {
    SiftCorpus k;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
    if (box.empty() || graf.empty()) {
      k.error = "box.png or graf1.png missing (install opencv-doc)";
      return k;
    }
    k.models.resize(2);
    Status s = build_model(box, "box", sift_params(), k.models[0]);
    if (s)
      s = build_model(graf(cv::Rect(300, 220, 200, 200)).clone(), "graf1_crop", sift_params(),
                      k.models[1]);
    if (s) s = serialize_index(k.models, sift_params(), k.bytes);
    if (!s) k.error = s.message();
    return k;
  }();
  return c;
}

std::uint32_t section_count_field(const Bytes& b, std::uint32_t id) {
  return load<std::uint32_t>(b.data() + entry(b, id) + format::kEntCount);
}

// Recomputes the CRC of section `id` and the header CRC.
void reseal_section(Bytes& b, std::uint32_t id) {
  store<std::uint32_t>(b.data() + entry(b, id) + format::kEntCrc,
                       crc32(b.data() + section_offset(b, id), section_size(b, id)));
  fix_header_crc(b);
}

TEST_F(ModelIndexTest, DefaultIndexHasEmptyVertexDescriptorSection) {
  EXPECT_EQ(section_count(bytes()), format::kLastSectionId);
  EXPECT_EQ(section_count_field(bytes(), format::kSectionVertexDescriptors), 0u);
  EXPECT_EQ(section_size(bytes(), format::kSectionVertexDescriptors), 0u);
  AlignedBytes buffer(bytes());
  ModelIndex index;
  ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
  EXPECT_EQ(index.vertex_descriptors(), nullptr);
  EXPECT_EQ(index.params().descriptor.vertex_descriptor, VertexDescriptor::kNone);
  for (const BuiltModel& m : models()) EXPECT_TRUE(m.vertex_descriptors.empty());
}

TEST_F(ModelIndexTest, SiftVertexDescriptorsRoundTrip) {
  const SiftCorpus& sc = sift_corpus();
  ASSERT_TRUE(sc.error.empty()) << sc.error;
  Bytes all;
  std::size_t keypoints = 0;
  for (const BuiltModel& m : sc.models) {
    ASSERT_EQ(m.vertex_descriptors.size(), m.keypoints.size() * kVertexDescriptorSize) << m.name;
    ASSERT_EQ(m.keypoint_scales.size(), m.keypoints.size()) << m.name;
    all.insert(all.end(), m.vertex_descriptors.begin(), m.vertex_descriptors.end());
    keypoints += m.keypoints.size();
  }
  // Same keypoints and arcs as without vertex descriptors.
  EXPECT_EQ(sc.models[0].keypoints.size(), models()[0].keypoints.size());
  EXPECT_EQ(sc.models[0].arcs.size(), models()[0].arcs.size());
  const Bytes& b = sc.bytes;
  EXPECT_EQ(section_count_field(b, format::kSectionVertexDescriptors), keypoints);
  EXPECT_EQ(section_size(b, format::kSectionVertexDescriptors), keypoints * kVertexDescriptorSize);
  EXPECT_EQ(section_offset(b, format::kSectionVertexDescriptors) % format::kAlignment, 0u);

  AlignedBytes buffer(b);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  expect_matches(index, sc.models);
  expect_same_params(index.params(), sift_params());
  EXPECT_EQ(index.params().descriptor.vertex_descriptor, VertexDescriptor::kSift);
  EXPECT_EQ(index.params().descriptor.vertex_threshold, sift_params().descriptor.vertex_threshold);
  ASSERT_NE(index.vertex_descriptors(), nullptr);
  EXPECT_EQ(0, std::memcmp(index.vertex_descriptors(), all.data(), all.size()));
  // Zero copy, like every section.
  EXPECT_EQ(index.vertex_descriptors(),
            buffer.data() + section_offset(b, format::kSectionVertexDescriptors));
  // Not all zero: SIFT of textured images.
  std::size_t nonzero = 0;
  for (std::uint8_t v : all) nonzero += v != 0;
  EXPECT_GT(nonzero, all.size() / 4);

  // Deterministic, and written to a file the same way.
  Bytes again;
  ASSERT_TRUE(serialize_index(sc.models, sift_params(), again));
  EXPECT_TRUE(again == b);
}

TEST_F(ModelIndexTest, RejectsVertexDescriptorCountMismatch) {
  const SiftCorpus& sc = sift_corpus();
  ASSERT_TRUE(sc.error.empty()) << sc.error;
  const std::uint32_t id = format::kSectionVertexDescriptors;
  const std::uint32_t n = section_count_field(sc.bytes, id);
  ASSERT_GT(n, 1u);

  // One descriptor short (size and count agree, CRCs right).
  Bytes b = sc.bytes;
  store<std::uint32_t>(b.data() + entry(b, id) + format::kEntCount, n - 1);
  store<std::uint64_t>(b.data() + entry(b, id) + format::kEntSize,
                       std::uint64_t{n - 1} * kVertexDescriptorSize);
  reseal_section(b, id);
  EXPECT_TRUE(rejected(b, "vertex descriptors section: count " + std::to_string(n - 1) +
                              ", expected " + std::to_string(n)));

  // Count disagreeing with the size.
  b = sc.bytes;
  store<std::uint32_t>(b.data() + entry(b, id) + format::kEntCount, n + 1);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "vertex descriptors section: size"));

  // Parameters asking for SIFT on an index without descriptors...
  b = bytes();
  put_params(b, sift_params());
  EXPECT_TRUE(rejected(b, "vertex descriptors section: count 0, expected"));
  // ...and descriptors the parameters do not ask for.
  b = sc.bytes;
  put_params(b, paper_params());
  EXPECT_TRUE(
      rejected(b, "vertex descriptors section: count " + std::to_string(n) + ", expected 0"));

  // The section is required even when empty, and SIFT parameters need it.
  b = sc.bytes;
  store<std::uint32_t>(b.data() + entry(b, id) + format::kEntId, 99);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "vertex descriptors section missing"));

  // The payload is checksummed like every section.
  b = sc.bytes;
  b[section_offset(b, id) + 17] ^= 0x01;
  EXPECT_TRUE(rejected(b, "vertex descriptors section: checksum mismatch"));
}

TEST_F(ModelIndexTest, RejectsLeafBoundCountMismatch) {
  const std::uint32_t id = format::kSectionLeafBounds;
  const std::uint32_t n = section_count_field(bytes(), id);
  ASSERT_GE(n, 2u);
  ASSERT_EQ(n % 2, 0u);
  // Two bounds short (size and count agree, CRCs right): one leaf unbounded.
  Bytes b = bytes();
  const std::uint64_t point = section_size(b, id) / n;
  store<std::uint32_t>(b.data() + entry(b, id) + format::kEntCount, n - 2);
  store<std::uint64_t>(b.data() + entry(b, id) + format::kEntSize, (n - 2) * point);
  reseal_section(b, id);
  EXPECT_TRUE(rejected(b, "leaf bounds section: " + std::to_string(n - 2) + " points, expected " +
                              std::to_string(n) + " (two per leaf)"));
}

TEST_F(ModelIndexTest, RejectsBadVertexDescriptorParameters) {
  Params p;
  p.descriptor.vertex_descriptor = static_cast<VertexDescriptor>(2);
  Bytes b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter descriptor.vertex_descriptor"));
  for (float bad : {0.f, -0.5f, 2.5f, std::nanf("")}) {
    p = sift_params();
    p.descriptor.vertex_threshold = bad;
    b = sift_corpus().bytes;
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter descriptor.vertex_threshold")) << bad;
  }
  // Without vertex descriptors the threshold is unused and may be 0.
  p = paper_params();
  p.descriptor.vertex_threshold = 0.f;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(try_view(b));
}

TEST_F(ModelIndexTest, SerializeRejectsMissingVertexDescriptors) {
  Bytes b;
  // Models built without SIFT cannot go into an index that asks for it.
  const Status s = serialize_index(models(), sift_params(), b);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("box"), std::string::npos) << s.message();
  // The other way round, descriptors are left out.
  const SiftCorpus& sc = sift_corpus();
  ASSERT_TRUE(sc.error.empty()) << sc.error;
  ASSERT_TRUE(serialize_index(sc.models, paper_params(), b));
  EXPECT_TRUE(b == bytes()) << "models built with SIFT, written without, differ";
}

// --- Files --------------------------------------------------------------

Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_file(const std::filesystem::path& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

TEST_F(ModelIndexTest, WriteAndOpenFile) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::string path = (dir.path() / "models.kgi").string();
  Status s = write_index(models(), paper_params(), path);
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(read_file(path) == bytes()) << "file differs from serialize_index";
  EXPECT_EQ(dir.names(), std::vector<std::string>{"models.kgi"}) << "temporary file left";

  ModelIndex index;
  s = ModelIndex::open(path, index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(index.is_mapped()) << "open() maps regular files";
  expect_matches(index, models());
  expect_same_params(index.params(), paper_params());
  EXPECT_EQ(0, std::memcmp(index.data(), bytes().data(), bytes().size()));
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(index.data()) % format::kAlignment, 0u);

  // read(), open()'s fallback, copies into an aligned buffer.
  ModelIndex copied;
  s = ModelIndex::read(path, copied);
  ASSERT_TRUE(s) << s.message();
  EXPECT_FALSE(copied.is_mapped());
  expect_matches(copied, models());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(copied.data()) % format::kAlignment, 0u);
  // Moving keeps the mapping alive and valid.
  ModelIndex moved = std::move(index);
  EXPECT_TRUE(moved.is_mapped());
  expect_matches(moved, models());
  index = std::move(moved);

  // Overwriting an existing index replaces it whole.
  std::vector<BuiltModel> one = {models()[1]};
  ASSERT_TRUE(write_index(one, paper_params(), path));
  EXPECT_EQ(dir.names(), std::vector<std::string>{"models.kgi"});
  ModelIndex replaced;
  ASSERT_TRUE(ModelIndex::open(path, replaced));
  EXPECT_EQ(replaced.model_count(), 1);
  EXPECT_EQ(replaced.model(0).name, "graf1_crop");
  // The earlier index maps the replaced file (renamed over, so its inode
  // lives on) and is unaffected; so is the copy.
  EXPECT_EQ(index.model_count(), 2);
  EXPECT_EQ(index.model(1).name, "graf1_crop");
  expect_matches(index, models());
  expect_matches(copied, models());
}

TEST_F(ModelIndexTest, WriteIntoMissingDirectoryFails) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  const std::filesystem::path missing = dir.path() / "no_such_dir";
  const std::string path = (missing / "models.kgi").string();
  const Status s = write_index(models(), paper_params(), path);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find(path), std::string::npos) << s.message();
  EXPECT_FALSE(std::filesystem::exists(missing));
  EXPECT_TRUE(dir.names().empty()) << "something was left behind";
}

TEST_F(ModelIndexTest, OpenRejectsBadFiles) {
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  ModelIndex index;
  Status s = ModelIndex::open((dir.path() / "absent.kgi").string(), index);
  EXPECT_EQ(s.code(), StatusCode::kNotFound) << s.message();
  EXPECT_NE(s.message().find("absent.kgi"), std::string::npos) << s.message();

  const auto empty = dir.path() / "empty.kgi";
  write_file(empty, {});
  s = ModelIndex::open(empty.string(), index);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("too small"), std::string::npos) << s.message();

  const auto text = dir.path() / "text.kgi";
  const std::string words = "this is a text file, not an index, but long enough for a header....\n";
  write_file(text, Bytes(words.begin(), words.end()));
  s = ModelIndex::open(text.string(), index);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("magic"), std::string::npos) << s.message();

  const auto truncated = dir.path() / "truncated.kgi";
  write_file(truncated, Bytes(bytes().begin(), bytes().begin() + bytes().size() / 2));
  s = ModelIndex::open(truncated.string(), index);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("truncated"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("truncated.kgi"), std::string::npos) << "message names the file";
  // read() says the same.
  s = ModelIndex::read(truncated.string(), index);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("truncated"), std::string::npos) << s.message();
  s = ModelIndex::read((dir.path() / "absent.kgi").string(), index);
  EXPECT_EQ(s.code(), StatusCode::kNotFound) << s.message();
  s = ModelIndex::read(dir.path().string(), index);
  EXPECT_FALSE(s);
  EXPECT_TRUE(index.empty());
}

TEST_F(ModelIndexTest, OpenRejectsDirectory) {
  // fopen() succeeds on a directory on Linux and ftell() then reports a
  // huge size: open() must say so, not throw or abort on the allocation.
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  ModelIndex index;
  const Status s = ModelIndex::open(dir.path().string(), index);
  EXPECT_FALSE(s);
  EXPECT_FALSE(s.message().empty());
  EXPECT_TRUE(index.empty()) << "failed opens leave the output untouched";
}

// --- Allocation ---------------------------------------------------------------

// view() of a valid index allocates nothing, whatever its size or encoding;
// open() maps, so its allocations do not grow with the file either.
TEST_F(ModelIndexTest, ViewAllocatesNothing) {
  std::vector<const Bytes*> all = {&bytes(), &small_corpus().small};
  for (DescriptorEncoding e : kEncodings) all.push_back(&encoded(e));
  if (sift_corpus().error.empty()) all.push_back(&sift_corpus().bytes);
  for (const Bytes* b : all) {
    AlignedBytes buffer(*b);
    ModelIndex index;
    long allocations = 0;
    {
      test::AllocationCounter counter;
      const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
      allocations = counter.count();
      ASSERT_TRUE(s) << s.message();
    }
    EXPECT_EQ(allocations, 0) << b->size() << "-byte index";
    // Nor does the search: a query through the index.
    const ArcSearch search(index);
    std::uint32_t out[256];
    test::AllocationCounter counter;
    const std::uint32_t found = search.radius_search(models()[0].descriptors[0], nullptr, out, 256);
    EXPECT_EQ(counter.count(), 0);
    (void)found;
  }
  TempDir dir;
  ASSERT_FALSE(dir.path().empty());
  long opened[2] = {0, 0};
  const Bytes* files[2] = {&small_corpus().small, &bytes()};
  for (int i = 0; i < 2; ++i) {
    const std::string path = (dir.path() / ("f" + std::to_string(i) + ".kgi")).string();
    write_file(path, *files[i]);
    ModelIndex index;
    test::AllocationCounter counter;
    const Status s = ModelIndex::open(path, index);
    opened[i] = counter.count();
    ASSERT_TRUE(s) << s.message();
    ASSERT_TRUE(index.is_mapped());
  }
  EXPECT_EQ(opened[0], opened[1]) << "open() allocations grow with the file";
  EXPECT_LE(opened[1], 2);
}

// --- Golden files -------------------------------------------------------------
//
// tests/data/golden-<major>.<minor>-<encoding>.kgi: the 96x96 crop at
// (100, 50) of opencv-doc's box.png, model name "box_crop", default
// parameters except the encoding. The current version's files must be what
// the writer produces today, byte for byte; every golden file in
// tests/data, including earlier minor versions', must load and detect the
// crop in box.png (readers keep reading earlier minor versions).
//
// After a deliberate format or default-parameter change, regenerate the
// current version's files and commit them:
//   KG_UPDATE_GOLDEN=1 <build>/tests/test_model_index --gtest_filter='Golden*'
// A new minor version writes new file names: keep the old files. Bytes can
// also differ on another platform (the reference is x86-64 Debian bookworm,
// g++ 12, OpenCV 4.6: float rounding, FMA contraction, resampling): there,
// treat a mismatch as a finding to investigate, not a file to regenerate.

constexpr DescriptorEncoding kGoldenEncodings[] = {DescriptorEncoding::kFloat32,
                                                   DescriptorEncoding::kInt8};
const cv::Rect kGoldenCrop(100, 50, 96, 96);

std::filesystem::path golden_dir() {
  // This file is tests/core/test_model_index.cpp; the goldens are in tests/data.
  return std::filesystem::path(__FILE__).parent_path().parent_path() / "data";
}

std::filesystem::path golden_path(DescriptorEncoding e) {
  return golden_dir() / ("golden-" + std::to_string(format::kVersionMajor) + "." +
                         std::to_string(format::kVersionMinor) + "-" + encoding_name(e) + ".kgi");
}

// graph.max_neighbour_rank (format 6.6): built from one image (no views),
// the arcs stored are exactly those of every pair in range (rank 0) whose
// ends are, one of them, among the other's K nearest keypoints in range;
// a rank above the keypoint count stores every pair as rank 0 does.
TEST(ModelBuilder, ArcsJoinNearNeighboursOnly) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  Params params;
  params.views.min_size = 0.f;  // one image at the legacy scales
  auto build = [&](int rank, BuiltModel& out) {
    params.graph.max_neighbour_rank = rank;
    return build_model(box, "box", params, out);
  };
  BuiltModel every, near, beyond;
  ASSERT_TRUE(build(0, every));
  constexpr int kRank = 8;
  ASSERT_TRUE(build(kRank, near));
  ASSERT_TRUE(build(1 << 20, beyond));
  auto pairs = [](const BuiltModel& m) {
    std::set<std::pair<std::uint32_t, std::uint32_t>> out;
    for (const ModelArc& a : m.arcs) out.insert({a.from, a.to});
    return out;
  };
  EXPECT_EQ(pairs(beyond), pairs(every));
  ASSERT_EQ(near.keypoints.size(), every.keypoints.size());
  const std::size_t n = every.keypoints.size();
  ASSERT_GT(n, static_cast<std::size_t>(4 * kRank));
  // Each keypoint's K-th nearest partner in arc range, as the builder ranks
  // (float differences, squared and summed in double).
  auto length2 = [&](std::size_t a, std::size_t b) {
    const double dx = every.keypoints[b].x - every.keypoints[a].x;
    const double dy = every.keypoints[b].y - every.keypoints[a].y;
    return dx * dx + dy * dy;
  };
  std::vector<double> radius2(n, std::numeric_limits<double>::infinity());
  for (std::size_t a = 0; a < n; ++a) {
    std::vector<double> d2;
    for (std::size_t b = 0; b < n; ++b)
      if (b != a && is_model_arc(every.keypoints[a], every.keypoints[b], every.keypoint_scales[a],
                                 every.keypoint_scales[b], params.graph))
        d2.push_back(length2(a, b));
    if (d2.size() <= static_cast<std::size_t>(kRank)) continue;
    std::sort(d2.begin(), d2.end());
    radius2[a] = d2[kRank - 1];
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> expected;
  for (const auto& [from, to] : pairs(every))
    if (length2(from, to) <= radius2[from] || length2(from, to) <= radius2[to])
      expected.insert({from, to});
  EXPECT_EQ(pairs(near), expected);
  // Near neighbours are a small part of the pairs in range.
  EXPECT_LT(4 * near.arcs.size(), every.arcs.size());
  EXPECT_GT(near.arcs.size(), n * static_cast<std::size_t>(kRank) / 2);
}

// The same through the views of the defaults: each view describes at most
// 2 K arcs a keypoint (K nearest of each end, both directions), a bound the
// every-pair build exceeds; the stored keypoint pairs are a subset of the
// every-pair build's, and a small part of them.
TEST(ModelBuilder, EveryViewKeepsNearNeighbourArcsOnly) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  Params params;  // views on
  ASSERT_EQ(params.graph.max_neighbour_rank, 24);
  const auto rank = static_cast<long>(params.graph.max_neighbour_rank);
  BuiltModel near, every;
  ASSERT_TRUE(build_model(box, "box", params, near));
  params.graph.max_neighbour_rank = 0;
  ASSERT_TRUE(build_model(box, "box", params, every));
  ASSERT_EQ(near.views.size(), every.views.size());
  ASSERT_GT(near.views.size(), 4u);
  ASSERT_EQ(near.keypoints.size(), every.keypoints.size());
  bool bound_binds = false;
  for (std::size_t v = 0; v < near.views.size(); ++v) {
    SCOPED_TRACE("view " + std::to_string(v));
    ASSERT_EQ(near.views[v].keypoints, every.views[v].keypoints);
    const long bound = 2 * rank * near.views[v].keypoints;
    EXPECT_LE(near.views[v].view_arcs, bound);
    EXPECT_LE(near.views[v].view_arcs, every.views[v].view_arcs);
    bound_binds = bound_binds || every.views[v].view_arcs > bound;
  }
  EXPECT_TRUE(bound_binds) << "no view has more pairs in range than the rank keeps";
  std::set<std::pair<std::uint32_t, std::uint32_t>> all;
  for (const ModelArc& a : every.arcs) all.insert({a.from, a.to});
  for (const ModelArc& a : near.arcs)
    ASSERT_TRUE(all.count({a.from, a.to}) == 1) << a.from << " -> " << a.to;
  EXPECT_LT(3 * near.arcs.size(), every.arcs.size());
}

// An index built through views (the defaults): several arcs may join one
// keypoint pair (described in different views), every keypoint carries the
// range of views that detected it, and the tree points hold the attributes
// each arc's view measured.
TEST(ModelViewsIndex, ViewRangesAndViewAttributesRoundTrip) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty());
  const Params params;  // views on
  ASSERT_GT(params.views.min_size, 0.f);
  std::vector<BuiltModel> models(1);
  ASSERT_TRUE(build_model(box, "box", params, models[0]));
  const BuiltModel& bm = models[0];
  ASSERT_GT(bm.views.size(), 4u);
  ASSERT_EQ(bm.keypoint_views.size(), bm.keypoints.size());
  ASSERT_EQ(bm.arc_attributes.size(), bm.arcs.size());
  Bytes b;
  ASSERT_TRUE(serialize_index(models, params, b));
  AlignedBytes buffer(b);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  // Poses as small as the smallest view are plausible for this model only:
  // box.png's long edge is 324 px; a 64 px model keeps the symmetric limit.
  const double linear = params.views.min_size / (1.5 * 324.0);
  EXPECT_DOUBLE_EQ(smallest_area_scale(index.params(), 324.f, 223.f), linear * linear);
  EXPECT_DOUBLE_EQ(smallest_area_scale(index.params(), 64.f, 64.f),
                   1.0 / params.ransac.max_scale_change);
  int coarse = 0;
  for (std::uint32_t i = 0; i < index.keypoint_count(); ++i) {
    const std::uint8_t lo = index.keypoint_views()[2 * i], hi = index.keypoint_views()[2 * i + 1];
    EXPECT_EQ(lo, bm.keypoint_views[i][0]);
    EXPECT_EQ(hi, bm.keypoint_views[i][1]);
    EXPECT_LE(lo, hi);
    coarse += lo >= 8 ? 1 : 0;  // first seen at half size or smaller
  }
  EXPECT_GT(coarse, 0) << "no keypoint is new in a smaller view";
  // Every built arc is in the tree with its view's attributes (a multiset:
  // one pair may have several arcs).
  std::multimap<std::pair<std::uint32_t, std::uint32_t>, std::array<float, 2>> built;
  for (std::size_t i = 0; i < bm.arcs.size(); ++i)
    built.insert({{bm.arcs[i].from, bm.arcs[i].to}, bm.arc_attributes[i]});
  ASSERT_EQ(index.arc_count(), bm.arcs.size());
  const ArcSearchPointI8* points = IndexInternals::tree_points_i8(index);
  ASSERT_NE(points, nullptr);
  for (std::uint32_t slot = 0; slot < index.arc_count(); ++slot) {
    const ModelArc a = index.arc(slot);
    const auto range = built.equal_range({a.from, a.to});
    ASSERT_NE(range.first, range.second) << "slot " << slot << " holds an unknown arc";
    bool match = false;
    for (auto it = range.first; it != range.second && !match; ++it)
      match = points[slot][kDescriptorSize] == static_cast<std::int8_t>(it->second[0]) &&
              points[slot][kDescriptorSize + 1] == static_cast<std::int8_t>(it->second[1]);
    EXPECT_TRUE(match) << "slot " << slot << ": attributes of no view's arc";
  }
}

TEST(Golden, RebuildIsByteIdentical) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  ASSERT_TRUE(std::filesystem::is_directory(golden_dir())) << golden_dir();
  const char* update = std::getenv("KG_UPDATE_GOLDEN");
  for (DescriptorEncoding e : kGoldenEncodings) {
    SCOPED_TRACE(golden_path(e).string());
    const Params params = with_encoding(e, Params{});  // the defaults: views on
    std::vector<BuiltModel> models(1);
    ASSERT_TRUE(build_model(box(kGoldenCrop).clone(), "box_crop", params, models[0]));
    // With its quality report, as keygraph build writes it.
    QualityReport quality;
    ASSERT_TRUE(measure_quality(models, {box(kGoldenCrop).clone()}, params, {}, quality));
    Bytes rebuilt;
    ASSERT_TRUE(serialize_index(models, params, rebuilt, &quality));
    if (update != nullptr && std::string(update) == "1") {
      const Status s = write_index(models, params, golden_path(e).string(), &quality);
      ASSERT_TRUE(s) << s.message();
      std::printf("wrote %s (%zu bytes)\n", golden_path(e).string().c_str(), rebuilt.size());
      continue;
    }
    const Bytes golden = read_file(golden_path(e));
    ASSERT_FALSE(golden.empty()) << "missing; run with KG_UPDATE_GOLDEN=1 to create it";
    EXPECT_EQ(golden.size(), rebuilt.size());
    std::size_t first = 0;
    while (first < golden.size() && first < rebuilt.size() && golden[first] == rebuilt[first])
      ++first;
    EXPECT_TRUE(golden == rebuilt)
        << "the writer no longer reproduces the golden file (first difference at byte " << first
        << "). If the format or the defaults changed on purpose, regenerate: see the comment "
           "above this test";
  }
}

TEST(Golden, EveryGoldenLoadsAndDetects) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  std::vector<std::filesystem::path> goldens;
  std::error_code ec;
  for (const auto& f : std::filesystem::directory_iterator(golden_dir(), ec)) {
    const std::string name = f.path().filename().string();
    if (name.rfind("golden-", 0) == 0 && f.path().extension() == ".kgi")
      goldens.push_back(f.path());
  }
  std::sort(goldens.begin(), goldens.end());
  ASSERT_GE(goldens.size(), 2u) << "no golden files in " << golden_dir();
  std::set<int> minors;  // every minor version of this major must have its files
  for (const auto& path : goldens) {
    SCOPED_TRACE(path.filename().string());
    ModelIndex index;
    const Status s = ModelIndex::open(path.string(), index);
    ASSERT_TRUE(s) << s.message();
    minors.insert(index.version_minor());
    ASSERT_EQ(index.model_count(), 1);
    EXPECT_EQ(index.model(0).name, "box_crop");
    // From 6.2 on the crop's own pixels (96 px: below the 128 px appearance
    // size, so not resampled); earlier files have no appearance and read
    // the new parameters as 0.
    // The search budget grows from 6.3 on; older files keep it fixed.
    EXPECT_EQ(index.params().descriptor.search_reference_models,
              index.version_minor() >= 3 ? 10 : 0);
    // The triangle patch check (6.4) is on (0.6) in the files of 6.5's
    // defaults and off in older ones (their zero, or the default then).
    EXPECT_EQ(index.params().ransac.min_triangle_correlation,
              index.version_minor() >= 5 ? 0.6f : 0.f);
    // Progressive sampling (6.4) is on by default; older files draw uniformly.
    EXPECT_EQ(index.params().ransac.progressive_sampling, index.version_minor() >= 4 ? 1 : 0);
    // Circuit completion (6.5) is on by default, off in older files.
    EXPECT_EQ(index.params().graph.complete_circuits, index.version_minor() >= 5 ? 1 : 0);
    // Near-neighbour arcs (6.6): 24 by default; older files joined every pair.
    EXPECT_EQ(index.params().graph.max_neighbour_rank, index.version_minor() >= 6 ? 24 : 0);
    // No views larger than the model image (6.7): the default, and what
    // older files' zero reads as.
    EXPECT_EQ(index.params().views.max_scale, 1.f);
    // Fine Hessian levels (6.8): one by default; older files' zero is none.
    EXPECT_EQ(index.params().keypoints.hessian_fine_levels, index.version_minor() >= 8 ? 1 : 0);
    // Sub-pixel arc profiles (6.9) are opt-in: every golden file holds 0.
    EXPECT_EQ(index.params().descriptor.subpixel_profiles, 0);
    // The small-instance rule (6.10): on by default; older files' zeros are off.
    EXPECT_EQ(index.params().ransac.small_max_size, index.version_minor() >= 10 ? 150.f : 0.f);
    EXPECT_EQ(index.params().ransac.small_min_inliers, index.version_minor() >= 10 ? 6 : 0);
    EXPECT_EQ(index.params().ransac.small_min_appearance,
              index.version_minor() >= 10 ? 0.75f : 0.f);
    // Blurred small views (6.11, past the first 256 bytes) are opt-in: every
    // golden file holds 0, the older ones through their shorter block.
    EXPECT_EQ(index.params().views.blurred_max_size, 0.f);
    // Glowing small views (6.12) are opt-in: every golden file holds 0.
    EXPECT_EQ(index.params().views.glow_max_size, 0.f);
    if (index.version_minor() >= 2) {
      ASSERT_TRUE(index.has_appearance());
      const ModelAppearance look = index.appearance(0);
      ASSERT_EQ(look.width, kGoldenCrop.width);
      ASSERT_EQ(look.height, kGoldenCrop.height);
      EXPECT_EQ(look.scale, 1.f);
      const cv::Mat crop = box(kGoldenCrop).clone();
      EXPECT_EQ(0, std::memcmp(look.pixels, crop.data, crop.total()));
    } else {
      EXPECT_FALSE(index.has_appearance());
      EXPECT_TRUE(index.appearance(0).empty());
      EXPECT_EQ(index.max_appearance_pixels(), 0);
      EXPECT_EQ(index.params().views.appearance_size, 0);
      EXPECT_EQ(index.params().ransac.min_appearance, 0.f);
    }
    DesktopDetector detector(index);
    DetectionList found;
    ASSERT_TRUE(detector.detect(box, found));
    ASSERT_EQ(found.size(), 1u);
    EXPECT_EQ(found[0].model_id, 0);
    const float x0 = static_cast<float>(kGoldenCrop.x), y0 = static_cast<float>(kGoldenCrop.y);
    const float x1 = x0 + static_cast<float>(kGoldenCrop.width - 1);
    const float y1 = y0 + static_cast<float>(kGoldenCrop.height - 1);
    const Point2f want[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(found[0].corners[c].x, want[c].x, 3.f) << "corner " << c;
      EXPECT_NEAR(found[0].corners[c].y, want[c].y, 3.f) << "corner " << c;
    }
  }
  for (int minor = 0; minor <= format::kVersionMinor; ++minor)
    EXPECT_EQ(minors.count(minor), 1u) << "no golden file of format 6." << minor;
}

// --- Corruption -------------------------------------------------------------

TEST_F(ModelIndexTest, RejectsBadMagic) {
  Bytes b = bytes();
  b[0] = 'X';
  EXPECT_TRUE(rejected(b, "bad magic"));
  b = bytes();
  std::memcpy(b.data() + 1, "PNG", 3);
  EXPECT_TRUE(rejected(b, "not a keygraph index"));
  b = bytes();
  b[7] = 0;  // the trailing LF of the magic
  EXPECT_TRUE(rejected(b, "bad magic"));
}

TEST_F(ModelIndexTest, RejectsTextModeDamage) {
  // CR LF -> LF over the whole file, as a text-mode transfer would do.
  Bytes lf;
  for (std::size_t i = 0; i < bytes().size(); ++i) {
    if (bytes()[i] == '\r' && i + 1 < bytes().size() && bytes()[i + 1] == '\n') continue;
    lf.push_back(bytes()[i]);
  }
  ASSERT_LT(lf.size(), bytes().size());
  EXPECT_TRUE(rejected(lf, "text-mode"));

  // LF -> CR LF, the other direction.
  Bytes crlf;
  for (std::uint8_t c : bytes()) {
    if (c == '\n') crlf.push_back('\r');
    crlf.push_back(c);
  }
  EXPECT_TRUE(rejected(crlf, "text-mode"));
}

TEST_F(ModelIndexTest, RejectsTruncation) {
  const std::size_t n = bytes().size();
  std::vector<std::size_t> lengths = {0,
                                      1,
                                      8,
                                      12,
                                      40,
                                      format::kHeaderSize - 1,
                                      format::kHeaderSize,
                                      table_end(bytes()) - 1,
                                      table_end(bytes())};
  for (std::size_t k = 1; k < 50; ++k) lengths.push_back(n * k / 50);
  for (std::size_t k = 1; k <= 8; ++k) lengths.push_back(n - k);
  for (std::size_t len : lengths) {
    SCOPED_TRACE("length " + std::to_string(len) + " of " + std::to_string(n));
    const Bytes cut(bytes().begin(), bytes().begin() + static_cast<std::ptrdiff_t>(len));
    const Status s = try_view(cut);
    ASSERT_FALSE(s);
    EXPECT_TRUE(s.message().find("truncated") != std::string::npos ||
                s.message().find("too small") != std::string::npos)
        << s.message();
  }
  // Trailing bytes are damage too.
  Bytes padded = bytes();
  padded.resize(n + 64, 0);
  EXPECT_TRUE(rejected(padded, "padded"));
}

TEST_F(ModelIndexTest, RejectsOtherMajorVersion) {
  for (std::uint16_t major :
       {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{2}, std::uint16_t{3}, std::uint16_t{4},
        std::uint16_t{5}, std::uint16_t{7}, std::uint16_t{0xFFFF}}) {
    Bytes b = bytes();
    store<std::uint16_t>(b.data() + format::kOffMajor, major);
    fix_header_crc(b);
    EXPECT_TRUE(
        rejected(b, "version " + std::to_string(major) + ".", StatusCode::kUnsupportedVersion));
    // Older files: rebuild them; newer ones: update the reader.
    EXPECT_TRUE(rejected(b, major < format::kVersionMajor ? "rebuild the index" : "newer keygraph",
                         StatusCode::kUnsupportedVersion));
  }
  // A real 3.0 file (as keygraph 3.0 wrote it: scale attributes on another
  // scale, no leaf bounds) says which version it is and what to do.
  const Bytes old = read_file(golden_dir() / "format-3.0-int8.kgi");
  ASSERT_FALSE(old.empty());
  EXPECT_TRUE(rejected(old,
                       "index format version 3.0 is not supported (this reader reads 6.x): "
                       "rebuild the index",
                       StatusCode::kUnsupportedVersion));
  // A real 4.0 file (its tree has leaves of up to 32 arcs, so its sections
  // do not add up at 64): the same.
  const Bytes v4 = read_file(golden_dir() / "format-4.0-int8.kgi");
  ASSERT_FALSE(v4.empty());
  EXPECT_TRUE(rejected(v4,
                       "index format version 4.0 is not supported (this reader reads 6.x): "
                       "rebuild the index",
                       StatusCode::kUnsupportedVersion));
  // A real 5.0 file (no views, no keypoint views section): the same.
  const Bytes v5 = read_file(golden_dir() / "format-5.0-int8.kgi");
  ASSERT_FALSE(v5.empty());
  EXPECT_TRUE(rejected(v5,
                       "index format version 5.0 is not supported (this reader reads 6.x): "
                       "rebuild the index",
                       StatusCode::kUnsupportedVersion));
  // A newer minor version of the same major is readable (new sections and
  // parameters are additive).
  Bytes b = bytes();
  store<std::uint16_t>(b.data() + format::kOffMinor, 9);
  fix_header_crc(b);
  AlignedBytes buffer(b);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(index.version_minor(), 9);
}

TEST_F(ModelIndexTest, RandomBytesAfterMagicAreDamageNotANewerVersion) {
  // The magic followed by noise (issue 15: reported as "version 57974.33130
  // written by a newer keygraph"): the version is implausible and the header
  // checksum fails, so it is damage.
  std::uint32_t lcg = 2024;
  for (int trial = 0; trial < 50; ++trial) {
    Bytes b = bytes();
    for (std::size_t i = sizeof(format::kMagic); i < b.size(); ++i)
      b[i] = static_cast<std::uint8_t>((lcg = lcg * 1664525u + 1013904223u) >> 24);
    if (load<std::uint16_t>(b.data() + format::kOffMajor) == format::kVersionMajor) continue;
    const Status s = try_view(b);
    ASSERT_FALSE(s.is_ok());
    EXPECT_EQ(s.message().find("newer keygraph"), std::string::npos) << s.message();
    EXPECT_EQ(s.message().find("rebuild"), std::string::npos) << s.message();
  }
  // The case of the report: version 57974.33130, header checksum wrong.
  Bytes b = bytes();
  store<std::uint16_t>(b.data() + format::kOffMajor, 57974);
  store<std::uint16_t>(b.data() + format::kOffMinor, 33130);
  EXPECT_TRUE(rejected(b, "header: damaged (version field 57974.33130 is not a keygraph version"));
  // A plausible newer version with a broken checksum is still named.
  b = bytes();
  store<std::uint16_t>(b.data() + format::kOffMajor, format::kVersionMajor + 1);
  EXPECT_TRUE(rejected(b, "newer keygraph", StatusCode::kUnsupportedVersion));
}

TEST_F(ModelIndexTest, RejectsHeaderDamage) {
  // Without a fixed CRC, any header, parameter or table byte is caught.
  for (std::size_t at : {std::size_t{format::kOffFileSize + 7}, std::size_t{format::kOffHeaderCrc},
                         std::size_t{format::kHeaderSize + 3}, table_end(bytes()) - 1}) {
    Bytes b = bytes();
    b[at] ^= 0x10;
    EXPECT_TRUE(rejected(b, "header")) << "byte " << at;
  }
  Bytes b = bytes();
  store<std::uint32_t>(b.data() + format::kOffHeaderCrc,
                       load<std::uint32_t>(b.data() + format::kOffHeaderCrc) ^ 1u);
  EXPECT_TRUE(rejected(b, "header: checksum mismatch"));

  // With the CRC fixed, the structural checks must fire on their own.
  b = bytes();
  store<std::uint32_t>(b.data() + format::kOffHeaderSize, 128);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "header: size field"));
  b = bytes();
  store<std::uint32_t>(b.data() + format::kOffParamsOffset, 0xFFFFFF00u);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "parameter block out of bounds"));
  b = bytes();
  store<std::uint32_t>(b.data() + format::kOffSectionCount, 0);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "section count"));
  b = bytes();
  store<std::uint32_t>(b.data() + format::kOffTableOffset, 0xFFFFFFC0u);
  store<std::uint32_t>(b.data() + format::kOffHeaderCrc, 0);  // CRC is checked after bounds
  EXPECT_TRUE(rejected(b, "section table out of bounds"));
}

TEST_F(ModelIndexTest, RejectsFlippedByteInEachSection) {
  for (std::uint32_t id = 1; id <= format::kLastSectionId; ++id) {
    // The vertex descriptor and quality sections are empty here (the SIFT
    // and quality tests cover them).
    if (id == format::kSectionVertexDescriptors ||
        (id >= format::kSectionModelQuality && id <= format::kSectionLookAlikes))
      continue;
    const char* name = format::section_name(id);
    ASSERT_GT(section_size(bytes(), id), 0u) << name;
    for (std::size_t where :
         {std::size_t{0}, section_size(bytes(), id) / 2, section_size(bytes(), id) - 1}) {
      Bytes b = bytes();
      b[section_offset(b, id) + where] ^= 0x01;
      EXPECT_TRUE(rejected(b, std::string(name) + " section: checksum mismatch"))
          << name << " byte " << where;
    }
  }
}

TEST_F(ModelIndexTest, RejectsBadSectionTable) {
  const std::size_t e = entry(bytes(), format::kSectionTreeArcs);
  Bytes b = bytes();
  store<std::uint64_t>(b.data() + e + format::kEntOffset, b.size() + 64);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "tree arcs section: offset"));
  b = bytes();
  store<std::uint64_t>(b.data() + e + format::kEntSize, ~std::uint64_t{0} - 8);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "out of bounds"));
  b = bytes();
  store<std::uint64_t>(b.data() + e + format::kEntOffset,
                       load<std::uint64_t>(b.data() + e + format::kEntOffset) + 4);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "not 64-byte aligned"));
  // Section overlapping the header/table.
  b = bytes();
  store<std::uint64_t>(b.data() + e + format::kEntOffset, 0);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "out of bounds"));
  // Count disagreeing with size (CRC still right: the data did not change).
  b = bytes();
  store<std::uint32_t>(b.data() + e + format::kEntCount,
                       load<std::uint32_t>(b.data() + e + format::kEntCount) + 1);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "tree arcs section: size"));
  EXPECT_TRUE(rejected(b, "does not match count"));
  // Two tree-arcs sections; the tree-nodes section then missing.
  b = bytes();
  store<std::uint32_t>(b.data() + entry(b, format::kSectionTreeNodes) + format::kEntId,
                       format::kSectionTreeArcs);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "duplicate tree arcs section"));
  b = bytes();
  store<std::uint32_t>(b.data() + entry(b, format::kSectionTreeNodes) + format::kEntId, 99);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "tree nodes section missing"));
  // Every section is required, empty ones too.
  b = bytes();
  store<std::uint32_t>(b.data() + entry(b, format::kSectionVertexDescriptors) + format::kEntId, 99);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "vertex descriptors section missing"));
  // Descriptor, node and leaf-bound sections name the parameters' encoding.
  for (std::uint32_t id :
       {format::kSectionDescriptors, format::kSectionTreeNodes, format::kSectionLeafBounds}) {
    for (std::uint32_t bad : {0u, 1u, 2u, 3u, 0xFFFFFFFFu}) {
      if (bad == static_cast<std::uint32_t>(paper_params().descriptor.encoding)) continue;
      b = bytes();
      store<std::uint32_t>(b.data() + entry(b, id) + format::kEntEncoding, bad);
      fix_header_crc(b);
      EXPECT_TRUE(rejected(b, std::string(format::section_name(id)) + " section: encoding " +
                                  std::to_string(bad) + " differs from parameter encoding"));
    }
  }
}

TEST_F(ModelIndexTest, UnknownSectionsAreSkipped) {
  // A later minor version may add sections: an extra table entry (id 99,
  // here describing the strings' bytes) is ignored. The table grows by one
  // entry: every section moves 64 bytes on (alignment), as a writer of that
  // version would lay them out.
  const Bytes original = bytes();
  const std::size_t end = table_end(original);
  Bytes b(original.begin(), original.begin() + static_cast<std::ptrdiff_t>(end));
  b.resize(end + format::kAlignment, 0);
  b.insert(b.end(), original.begin() + static_cast<std::ptrdiff_t>(end), original.end());
  ASSERT_EQ(section_offset(original, format::kSectionModels) % format::kAlignment, 0u);
  for (std::size_t i = 0; i < section_count(b); ++i) {
    const std::size_t e = table_offset(b) + i * format::kSectionEntrySize + format::kEntOffset;
    store<std::uint64_t>(b.data() + e, load<std::uint64_t>(b.data() + e) + format::kAlignment);
  }
  std::memcpy(b.data() + end, b.data() + entry(b, format::kSectionStrings),
              format::kSectionEntrySize);
  store<std::uint32_t>(b.data() + end + format::kEntId, 99);
  store<std::uint32_t>(b.data() + format::kOffSectionCount,
                       static_cast<std::uint32_t>(section_count(b) + 1));
  store<std::uint64_t>(b.data() + format::kOffFileSize, static_cast<std::uint64_t>(b.size()));
  fix_header_crc(b);
  AlignedBytes buffer(b);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  expect_matches(index, models());
}

// Tree arc `slot`'s start, and its end written through the int16 offset.
std::size_t arc_from_at(const Bytes& b, std::uint32_t slot) {
  return section_offset(b, format::kSectionTreeArcs) + 4 * std::size_t{slot};
}
std::uint32_t arc_from(const Bytes& b, std::uint32_t slot) {
  return load<std::uint32_t>(b.data() + arc_from_at(b, slot));
}
void set_arc_to(Bytes& b, std::uint32_t slot, std::uint32_t to) {
  const std::int64_t offset = std::int64_t{to} - arc_from(b, slot);
  ASSERT_TRUE(offset >= -32768 && offset <= 32767);
  store<std::int16_t>(b.data() + section_offset(b, format::kSectionTreeArcTargets) + 2 * slot,
                      static_cast<std::int16_t>(offset));
}

TEST_F(ModelIndexTest, RejectsBadKeypointScale) {
  const std::size_t at = section_offset(bytes(), format::kSectionKeypointScales) + 4 * 3;
  for (float bad :
       {-1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    Bytes b = bytes();
    store<float>(b.data() + at, bad);
    reseal(b);
    EXPECT_TRUE(rejected(b, "keypoint 3: scale not finite or negative")) << bad;
  }
  Bytes b = bytes();
  const std::size_t e = entry(b, format::kSectionKeypointScales);
  store<std::uint32_t>(b.data() + e + format::kEntCount,
                       load<std::uint32_t>(b.data() + e + format::kEntCount) - 1);
  store<std::uint64_t>(b.data() + e + format::kEntSize,
                       section_size(b, format::kSectionKeypointScales) - 4);
  reseal(b);
  EXPECT_TRUE(rejected(b, "keypoint scales section: count"));
}

TEST_F(ModelIndexTest, RejectsOutOfRangeArcKeypoint) {
  const auto total =
      static_cast<std::uint32_t>(models()[0].keypoints.size() + models()[1].keypoints.size());
  const auto first_of_1 = static_cast<std::uint32_t>(models()[0].keypoints.size());
  // Past every keypoint.
  Bytes b = bytes();
  set_arc_to(b, 0, total);
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree arc 0: keypoint ids"));
  EXPECT_TRUE(rejected(b, "invalid (" + std::to_string(total) + " keypoints)"));
  b = bytes();
  store<std::uint32_t>(b.data() + arc_from_at(b, 7), 0xFFFFFFFFu);
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree arc 7: keypoint ids 4294967295"));
  // A valid keypoint, but of the other model than the arc's start.
  b = bytes();
  const std::uint32_t from = arc_from(b, 3);
  const std::uint32_t owner = from < first_of_1 ? 0 : 1;
  set_arc_to(b, 3, owner == 0 ? first_of_1 : 0);
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree arc 3: keypoint ids outside model " + std::to_string(owner)));
  // A loop.
  b = bytes();
  set_arc_to(b, 0, arc_from(b, 0));
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree arc 0:"));
}

TEST_F(ModelIndexTest, RejectsBadTreeNodesAndDescriptors) {
  // float32: node dimension, split not finite, descriptor not finite.
  const Bytes& f32 = encoded(DescriptorEncoding::kFloat32);
  std::size_t nodes = section_offset(f32, format::kSectionTreeNodes);
  Bytes b = f32;
  store<std::uint32_t>(b.data() + nodes + 4, static_cast<std::uint32_t>(kSearchDims));
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree nodes: node 0 has a bad split"));
  b = f32;
  store<float>(b.data() + nodes + 8 * 2, std::numeric_limits<float>::infinity());
  reseal(b);
  EXPECT_TRUE(rejected(b, "tree nodes: node 2 has a bad split"));
  b = f32;
  store<float>(
      b.data() + section_offset(b, format::kSectionDescriptors) + sizeof(ArcSearchPoint) * 9 + 4,
      std::nanf(""));
  reseal(b);
  EXPECT_TRUE(rejected(b, "descriptor 9: not finite"));

  // int16 and int8: dimension, split and components within [-scale, scale]
  // (so integer squared distances cannot overflow).
  for (DescriptorEncoding e : {DescriptorEncoding::kInt16, DescriptorEncoding::kInt8}) {
    SCOPED_TRACE(encoding_name(e));
    const Bytes& good = encoded(e);
    nodes = section_offset(good, format::kSectionTreeNodes);
    const std::size_t desc = section_offset(good, format::kSectionDescriptors);
    const auto scale = static_cast<std::int16_t>(encoding_scale(e));
    b = good;
    store<std::uint16_t>(b.data() + nodes + 4 * 1 + 2, static_cast<std::uint16_t>(kSearchDims));
    reseal(b);
    EXPECT_TRUE(rejected(b, "tree nodes: node 1 has a bad split"));
    for (std::int16_t bad :
         {static_cast<std::int16_t>(scale + 1), static_cast<std::int16_t>(-scale - 1)}) {
      if (e == DescriptorEncoding::kInt16 && bad > 0) continue;  // 32768 is not an int16
      b = good;
      store<std::int16_t>(b.data() + nodes + 4 * 3, bad);
      reseal(b);
      EXPECT_TRUE(rejected(b, "tree nodes: node 3 has a bad split")) << bad;
    }
    b = good;
    if (e == DescriptorEncoding::kInt16) {
      store<std::int16_t>(b.data() + desc + sizeof(ArcSearchPointI16) * 5 + 2, -32768);
    } else {
      b[desc + sizeof(ArcSearchPointI8) * 5 + 1] = 0x80;  // -128
    }
    reseal(b);
    EXPECT_TRUE(rejected(b, "descriptor 5: not finite or out of range"));
    // The extremes themselves are valid.
    b = good;
    if (e == DescriptorEncoding::kInt16) {
      store<std::int16_t>(b.data() + desc + sizeof(ArcSearchPointI16) * 5 + 2, -32767);
    } else {
      b[desc + sizeof(ArcSearchPointI8) * 5 + 1] = 0x81;  // -127
    }
    reseal(b);
    EXPECT_TRUE(try_view(b));
  }
}

TEST_F(ModelIndexTest, RejectsBadModelRecords) {
  const std::size_t rec0 = section_offset(bytes(), format::kSectionModels);
  const std::size_t rec1 = rec0 + format::kModelRecordSize;
  Bytes b = bytes();
  store<std::uint32_t>(b.data() + rec1 + format::kModKeypointBegin,
                       load<std::uint32_t>(b.data() + rec1 + format::kModKeypointBegin) + 1);
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 1: keypoint range not contiguous"));
  b = bytes();
  store<std::uint32_t>(b.data() + rec1 + format::kModKeypointCount, 0x7FFFFFFFu);
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 1: keypoint range out of bounds"));
  b = bytes();
  store<std::uint32_t>(b.data() + rec1 + format::kModKeypointCount,
                       load<std::uint32_t>(b.data() + rec1 + format::kModKeypointCount) - 1);
  reseal(b);
  EXPECT_TRUE(rejected(b, "keypoint ranges do not cover"));
  // Arc counts: their sum is the tree arc count, and each is the number of
  // arcs starting in the model.
  b = bytes();
  store<std::uint32_t>(b.data() + rec1 + format::kModArcCount, 0x7FFFFFFFu);
  reseal(b);
  EXPECT_TRUE(rejected(b, "models section: arc counts add up to"));
  b = bytes();
  store<std::uint32_t>(b.data() + rec0 + format::kModArcCount,
                       load<std::uint32_t>(b.data() + rec0 + format::kModArcCount) + 1);
  store<std::uint32_t>(b.data() + rec1 + format::kModArcCount,
                       load<std::uint32_t>(b.data() + rec1 + format::kModArcCount) - 1);
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 0: arc count " + std::to_string(models()[0].arcs.size() + 1) +
                              ", but " + std::to_string(models()[0].arcs.size()) +
                              " arcs start in it"));
  b = bytes();
  store<std::uint32_t>(b.data() + rec1 + format::kModNameLength, 1000);
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 1: name out of bounds"));
  b = bytes();
  store<float>(b.data() + rec1 + format::kModWidth, 0.f);
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 1: bad image size"));
  b = bytes();
  store<float>(b.data() + rec1 + format::kModOutline + 12, std::nanf(""));
  reseal(b);
  EXPECT_TRUE(rejected(b, "model 1: bad outline"));
  b = bytes();
  store<float>(b.data() + section_offset(b, format::kSectionKeypoints) + 8 * 3 + 4,
               std::numeric_limits<float>::infinity());
  reseal(b);
  EXPECT_TRUE(rejected(b, "keypoint 3: not finite"));
}

// What the format promises beyond bounds (docs/FORMAT.md, issue 40):
// reserved bytes are zero, the sections read do not overlap, and every
// outline corner lies on the model image. Each is refused with the CRCs
// repaired, so only the promise can reject it.
TEST_F(ModelIndexTest, RejectsReservedBytesOverlapsAndOutlinesOffTheImage) {
  const std::size_t rec1 =
      section_offset(bytes(), format::kSectionModels) + format::kModelRecordSize;
  for (std::size_t at = format::kOffHeaderCrc + 4; at < format::kHeaderSize; at += 7) {
    Bytes b = bytes();
    b[at] = 1;
    fix_header_crc(b);
    EXPECT_TRUE(rejected(b, "header: reserved byte " + std::to_string(at) + " is not zero"));
  }
  for (const std::size_t at : {format::kModReserved, format::kModOutline + 32 + 7}) {
    Bytes b = bytes();
    b[rec1 + at] = 1;
    reseal(b);
    EXPECT_TRUE(rejected(b, "model 1: reserved bytes are not zero")) << "byte " << at;
  }
  for (const float v : {1e30f, -1.f, 1e6f}) {
    Bytes b = bytes();
    store<float>(b.data() + rec1 + format::kModOutline + 12, v);
    reseal(b);
    EXPECT_TRUE(rejected(b, "model 1: bad outline")) << v;
  }
  // The keypoints section pointed at the models' bytes (sizes kept): the
  // CRC matches, the sections overlap.
  Bytes b = bytes();
  const std::size_t e = entry(b, format::kSectionKeypointScales);
  store<std::uint64_t>(b.data() + e + format::kEntOffset,
                       section_offset(b, format::kSectionKeypoints));
  reseal(b);
  EXPECT_TRUE(rejected(b, " section overlaps the "));
}

TEST_F(ModelIndexTest, RejectsBadParameterValues) {
  Params p;
  p.graph.structure = static_cast<Structure>(7);
  Bytes b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter graph.structure"));

  p = paper_params();
  p.keypoints.detector = static_cast<KeypointDetector>(9);
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter keypoints.detector"));

  p = paper_params();
  p.descriptor.similarity_threshold = std::nanf("");
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter descriptor.similarity_threshold"));

  p = paper_params();
  p.graph.min_distance = 200.f;  // above max_distance
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter graph.min_distance, graph.max_distance"));

  p = paper_params();
  p.ransac.max_instances = 0;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter ransac.max_instances"));

  p = paper_params();
  p.descriptor.encoding = static_cast<DescriptorEncoding>(3);
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter descriptor.encoding is unknown (3)"));
  // A valid encoding that is not the one the sections hold.
  for (DescriptorEncoding e : kEncodings) {
    for (DescriptorEncoding other : kEncodings) {
      if (other == e) continue;
      b = encoded(e);
      put_params(b, with_encoding(other));
      EXPECT_TRUE(rejected(
          b, "differs from parameter encoding " + std::to_string(static_cast<int>(other))));
    }
  }

  // The search budget (format 6.3).
  p = paper_params();
  p.descriptor.max_search_leaves = -1;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter descriptor.max_search_leaves must be >= 0"));
  for (const float correlation : {-0.5f, 1.f, std::numeric_limits<float>::quiet_NaN()}) {
    p = paper_params();
    p.ransac.min_triangle_correlation = correlation;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.min_triangle_correlation must be in [0, 1)"));
  }
  for (const int progressive : {-1, 2}) {
    p = paper_params();
    p.ransac.progressive_sampling = progressive;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.progressive_sampling must be 0"));
  }
  for (const int complete : {-1, 2}) {
    p = paper_params();
    p.graph.complete_circuits = complete;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter graph.complete_circuits must be 0"));
  }
  p = paper_params();
  p.graph.max_neighbour_rank = -1;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter graph.max_neighbour_rank must be >= 0"));
  for (const float scale : {0.5f, 4.5f, std::nanf("")}) {
    p = paper_params();
    p.views.max_scale = scale;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter views.max_scale must be in [1, 4]"));
  }
  // Within [1, 4] but above sqrt(ransac.max_scale_change), alone or with
  // a smaller max_scale_change.
  p = paper_params();
  p.views.max_scale = 3.f;
  p.ransac.max_scale_change = 8.0;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(
      rejected(b, "parameter views.max_scale must be at most sqrt(ransac.max_scale_change)"));
  p.views.max_scale = 2.f;
  p.ransac.max_scale_change = 3.0;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(
      rejected(b, "parameter views.max_scale must be at most sqrt(ransac.max_scale_change)"));
  // keypoints.hessian_fine_levels (issue 38): 0..hessian_levels, read back
  // as written; a negative fine threshold is refused.
  for (const int fine : {-1, 4}) {
    p = paper_params();
    p.keypoints.hessian_fine_levels = fine;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter keypoints.hessian_fine_levels must be in 0..")) << fine;
  }
  p = paper_params();
  p.keypoints.hessian_fine_threshold = -0.001f;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter keypoints.hessian_fine_threshold must be >= 0"));
  {
    p = paper_params();
    p.keypoints.hessian_fine_levels = 3;
    p.keypoints.hessian_fine_threshold = 0.0048f;
    b = bytes();
    put_params(b, p);
    AlignedBytes buffer(b);
    ModelIndex index;
    ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
    EXPECT_EQ(index.params().keypoints.hessian_fine_levels, 3);
    EXPECT_EQ(index.params().keypoints.hessian_fine_threshold, 0.0048f);
  }
  // descriptor.subpixel_profiles (issue 38): 0 or 1, read back as written.
  for (const int sub : {-1, 2}) {
    p = paper_params();
    p.descriptor.subpixel_profiles = sub;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter descriptor.subpixel_profiles must be 0 or 1")) << sub;
  }
  {
    p = paper_params();
    p.descriptor.subpixel_profiles = 1;
    b = bytes();
    put_params(b, p);
    AlignedBytes buffer(b);
    ModelIndex index;
    ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
    EXPECT_EQ(index.params().descriptor.subpixel_profiles, 1);
  }
  // ransac.small_* (issue 38, 6.10): ranges, 0 is off, read back as written.
  {
    p = paper_params();
    p.ransac.small_max_size = -1.f;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.small_max_size must be in [0, 100000]"));
    for (const int n : {-1, 3, 100001}) {
      p = paper_params();
      p.ransac.small_min_inliers = n;
      b = bytes();
      put_params(b, p);
      EXPECT_TRUE(rejected(b, "parameter ransac.small_min_inliers must be 0 (off) or in 4..100000"))
          << n;
    }
    p = paper_params();
    p.ransac.small_min_appearance = 1.5f;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.small_min_appearance must be in [-1, 1]"));
    p = paper_params();
    p.ransac.small_max_size = 90.f;
    p.ransac.small_min_inliers = 5;
    p.ransac.small_min_appearance = 0.85f;
    b = bytes();
    put_params(b, p);
    AlignedBytes buffer(b);
    ModelIndex index;
    ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
    EXPECT_EQ(index.params().ransac.small_max_size, 90.f);
    EXPECT_EQ(index.params().ransac.small_min_inliers, 5);
    EXPECT_EQ(index.params().ransac.small_min_appearance, 0.85f);
  }
  p = paper_params();
  p.descriptor.search_reference_models = -1;
  b = bytes();
  put_params(b, p);
  EXPECT_TRUE(rejected(b, "parameter descriptor.search_reference_models must be >= 0"));

  // The appearance parameters (format 6.2).
  for (const int size : {-1, 1, 15, 513, 1 << 30}) {
    p = paper_params();
    p.views.appearance_size = size;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter views.appearance_size must be 0 (none) or in 16..512"));
  }
  for (const int inliers : {-1, 1, 3, 100001}) {
    p = paper_params();
    p.ransac.confirmed_min_inliers = inliers;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(
        rejected(b, "parameter ransac.confirmed_min_inliers must be 0 (never) or in 4..100000"));
  }
  for (const float z : {-0.5f, 1001.f, std::nanf("")}) {
    p = paper_params();
    p.ransac.confirmed_min_verification_z = z;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.confirmed_min_verification_z must be in [0, 1000]"));
  }
  for (const float ncc : {-1.01f, 1.5f, std::nanf("")}) {
    p = paper_params();
    p.ransac.confirmed_min_appearance = ncc;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.confirmed_min_appearance must be in [-1, 1]"));
  }
  for (const float ncc : {-1.01f, 1.5f, std::nanf(""), std::numeric_limits<float>::infinity()}) {
    p = paper_params();
    p.ransac.min_appearance = ncc;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter ransac.min_appearance must be in [-1, 1]"));
  }
  // A field past the first 256 bytes of the block (6.11) is checked as well.
  for (const float size : {-1.f, 100001.f, std::nanf("")}) {
    p = paper_params();
    p.views.blurred_max_size = size;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter views.blurred_max_size must be in [0, 100000]"));
  }
  for (const float size : {-1.f, 100001.f, std::nanf("")}) {
    p = paper_params();
    p.views.glow_max_size = size;
    b = bytes();
    put_params(b, p);
    EXPECT_TRUE(rejected(b, "parameter views.glow_max_size must be in [0, 100000]"));
  }

  b = bytes();
  store<std::uint32_t>(b.data() + format::kOffParamsSize, 16);
  fix_header_crc(b);
  EXPECT_TRUE(rejected(b, "parameter block"));
}

// The block is at least 256 bytes (every reader since 2.0 asks that much)
// and grows in steps of 64 when the fields outgrow it; a reader takes a
// longer block than it knows (a later minor version's) by its known fields.
TEST(ParameterBlock, SizeFollowsTheFieldsAndLongerBlocksReadTheirKnownFields) {
  static_assert(format::kParamsSize >= format::kMinParamsSize);
  static_assert(format::kParamsSize % 64 == 0);
  static_assert(format::params_field_bytes() <= format::kParamsSize);
  static_assert(format::kParamsSize == format::kMinParamsSize ||
                format::params_field_bytes() > format::kParamsSize - 64);

  Params written;
  written.graph.min_distance = 9.f;
  written.ransac.small_min_inliers = 7;
  written.descriptor.encoding = DescriptorEncoding::kInt16;
  // A later writer's block: 128 more bytes, something in them.
  std::vector<std::uint8_t> longer(format::kParamsSize + 128, 0);
  format::serialize_params(written, longer.data());
  for (std::size_t i = format::kParamsSize; i < longer.size(); ++i) longer[i] = 0xA5;
  Params read;
  ASSERT_TRUE(format::parse_params(longer.data(), longer.size(), read));
  expect_same_params(read, written);
  EXPECT_EQ(read.graph.min_distance, 9.f);
  EXPECT_EQ(read.ransac.small_min_inliers, 7);

  // Shorter than every reader's minimum: refused.
  EXPECT_FALSE(format::parse_params(longer.data(), format::kMinParamsSize - 1, read));
}

TEST_F(ModelIndexTest, RejectsUnalignedOrNullBuffer) {
  for (std::size_t shift : {1u, 4u, 8u, 32u}) {
    AlignedBytes buffer(bytes(), shift);
    ModelIndex index;
    const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << shift;
    EXPECT_NE(s.message().find("aligned"), std::string::npos) << s.message();
    EXPECT_TRUE(index.empty());
  }
  ModelIndex index;
  EXPECT_FALSE(ModelIndex::view(nullptr, bytes().size(), index));
}

// One bit flipped at thousands of places, in each encoding: every flip
// inside a checksummed range (header..table, section payloads) must be
// rejected; a flip in alignment padding (checked by nothing) must load.
// Nothing may crash or read out of bounds (CI runs this under ASan).
TEST_F(ModelIndexTest, BitFlipSweep) {
  for (DescriptorEncoding e : kEncodings) {
    SCOPED_TRACE(encoding_name(e));
    const Bytes& good = small_corpus().small_encoded[static_cast<int>(e)];
    const std::size_t n = good.size();
    std::vector<bool> covered(n, false);
    for (std::size_t i = 0; i < table_end(good); ++i) covered[i] = true;
    for (std::uint32_t id = 1; id <= format::kLastSectionId; ++id) {
      const std::size_t off = section_offset(good, id), size = section_size(good, id);
      for (std::size_t i = off; i < off + size; ++i) covered[i] = true;
    }
    std::vector<std::size_t> positions;
    // Every byte of header, parameters and table (rejected early, so cheap)...
    for (std::size_t i = 0; i < table_end(good); ++i) positions.push_back(i);
    // ...and 2000 spread over the whole file, offset so they hit varied bytes.
    constexpr std::size_t kSpread = 2000;
    for (std::size_t k = 0; k < kSpread; ++k) positions.push_back((k * n) / kSpread + (k * 7) % 61);
    // Every padding byte range gets a flip at its start and end.
    for (std::size_t i = 1; i < n; ++i) {
      if (covered[i] != covered[i - 1]) {
        positions.push_back(i - 1);
        positions.push_back(i);
      }
    }
    positions.push_back(n - 1);

    AlignedBytes scratch(good);  // reused: copying per flip would dominate
    auto* data = const_cast<std::uint8_t*>(scratch.data());
    int rejected_count = 0, loaded = 0;
    for (std::size_t k = 0; k < positions.size(); ++k) {
      const std::size_t at = positions[k] < n ? positions[k] : n - 1;
      const auto mask = static_cast<std::uint8_t>(1u << (k % 8));
      data[at] ^= mask;
      ModelIndex index;
      const Status s = ModelIndex::view(data, n, index);
      data[at] ^= mask;
      if (s) {
        ++loaded;
        ASSERT_FALSE(covered[at]) << "flip of bit " << k % 8 << " at checksummed byte " << at
                                  << " was not detected";
        ASSERT_EQ(index.model_count(), 2);
      } else {
        ++rejected_count;
        ASSERT_FALSE(s.message().empty()) << "byte " << at;
        ASSERT_TRUE(covered[at]) << "flip at padding byte " << at << " rejected: " << s.message();
      }
    }
    EXPECT_GT(rejected_count, 2000);
    std::printf("bit-flip sweep (%s): %zu-byte index, %d flips rejected, %d in padding loaded\n",
                encoding_name(e), n, rejected_count, loaded);
    EXPECT_GT(loaded, 0) << "no flip landed in padding; the sweep misses the padding case";
    // The scratch buffer is back to the original.
    EXPECT_EQ(0, std::memcmp(data, good.data(), n));
  }
}

// Past the checksums: random bytes written into section payloads with every
// CRC recomputed, as a hostile file would. The reader's own checks must
// reject the damage or leave an index that searches and detects without
// fault (CI runs this under ASan and UBSan).
TEST_F(ModelIndexTest, ResealedMutationsAreRejectedOrHarmless) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty());
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  auto next = [&state] {  // xorshift64*: deterministic
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 0x2545F4914F6CDD1DULL;
  };
  for (DescriptorEncoding e : kEncodings) {
    SCOPED_TRACE(encoding_name(e));
    const Bytes& good = small_corpus().small_encoded[static_cast<int>(e)];
    int rejected_count = 0, loaded = 0, detected = 0;
    for (int k = 0; k < 1500; ++k) {
      Bytes b = good;
      // A section with bytes (1..6: models to tree nodes; 12..14: the
      // quality report; 15..16: the appearances), a byte in it.
      constexpr std::uint32_t kIds[] = {1, 2, 3, 4, 5, 6, 12, 13, 14, 15, 16};
      const std::uint32_t id = kIds[next() % std::size(kIds)];
      const std::size_t size = section_size(b, id);
      if (size == 0) continue;
      const std::size_t at = section_offset(b, id) + next() % size;
      const auto value = static_cast<std::uint8_t>(next());
      if (b[at] == value) continue;
      b[at] = value;
      reseal(b);
      AlignedBytes buffer(b);
      ModelIndex index;
      const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
      if (!s) {
        ++rejected_count;
        ASSERT_FALSE(s.message().empty());
        continue;
      }
      ++loaded;
      // Search with real descriptors; every slot returned indexes the arcs.
      const ArcSearch search(index);
      std::uint32_t out[512];
      for (std::size_t q = 0; q < models()[0].descriptors.size(); q += 997) {
        const std::uint32_t found =
            search.radius_search(models()[0].descriptors[q], nullptr, out, 512);
        for (std::uint32_t i = 0; i < std::min<std::uint32_t>(found, 512); ++i)
          ASSERT_LT(out[i], index.arc_count());
      }
      // And a full detection now and then (the slow part).
      if (loaded % 20 == 1) {
        DesktopDetector detector(index);
        DetectionList found;
        ASSERT_TRUE(detector.detect(box, found));
        ++detected;
      }
    }
    std::printf("resealed mutations (%s): %d rejected, %d loaded (%d detections run)\n",
                encoding_name(e), rejected_count, loaded, detected);
    EXPECT_GT(rejected_count, 0);
    EXPECT_GT(loaded, 0);
  }
}

// --- The quality report (format 6.1, sections 12-14) ----------------------

TEST_F(ModelIndexTest, QualityReportRoundTrips) {
  {
    // Written without a report: empty sections, none read back.
    AlignedBytes buffer(bytes());
    ModelIndex index;
    ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
    EXPECT_FALSE(index.has_quality());
    EXPECT_EQ(index.view_quality_count(), 0u);
    EXPECT_EQ(index.look_alike_count(), 0u);
  }
  const QualityReport& q = small_corpus().small_quality;
  const std::vector<BuiltModel>& small = small_corpus().small_models;
  ASSERT_EQ(q.models.size(), 2u);
  AlignedBytes buffer(small_corpus().small);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  ASSERT_TRUE(index.has_quality());
  ASSERT_EQ(index.view_quality_count(), q.views.size());
  for (int m = 0; m < 2; ++m) {
    const ModelQuality got = index.model_quality(m), want = q.models[m];
    EXPECT_EQ(got.view_begin, want.view_begin);
    EXPECT_EQ(got.view_count, small[m].views.size());
    EXPECT_EQ(got.shared_arcs, want.shared_arcs);
    EXPECT_LE(got.shared_arcs, small[m].arcs.size());
    EXPECT_EQ(got.smallest_size, want.smallest_size);
    EXPECT_GT(got.scene_size, 0.f);  // the look-alike check ran
    EXPECT_EQ(got.found_in_scene, want.found_in_scene);
    for (std::uint32_t v = 0; v < got.view_count; ++v) {
      const ViewQuality vq = index.view_quality(got.view_begin + v);
      const ViewSummary& built = small[m].views[v];
      EXPECT_EQ(vq.scale, static_cast<float>(built.scale));
      EXPECT_EQ(vq.keypoints, static_cast<std::uint32_t>(built.keypoints));
      EXPECT_EQ(vq.arcs, static_cast<std::uint32_t>(built.view_arcs));
      EXPECT_EQ(vq.keygraphs, built.keygraphs);
      EXPECT_GE(vq.arcs, static_cast<std::uint32_t>(built.arcs));  // before deduplication
    }
  }
  ASSERT_EQ(index.look_alike_count(), q.look_alikes.size());
  // Out-of-range requests give empty records, never a read out of bounds.
  EXPECT_EQ(index.model_quality(2).view_count, 0u);
  EXPECT_EQ(index.view_quality(index.view_quality_count()).keypoints, 0u);
}

// views.max_scale (format 6.7): the views larger than the model image are
// recorded with their scales, and an index holding them loads; the same
// scale in a view record is refused when the parameters do not allow it
// (RejectsBadQualitySections).
TEST(ModelIndexLargerViews, RecordsAndLoadsViewsUpToMaxScale) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  const cv::Mat crop = box(kGoldenCrop).clone();
  Params params;
  params.views.max_scale = 2.f;
  std::vector<BuiltModel> models(1);
  ASSERT_TRUE(build_model(crop, "box_crop", params, models[0]));
  Params frontal_only = params;
  frontal_only.views.max_scale = 1.f;
  BuiltModel without;
  ASSERT_TRUE(build_model(crop, "box_crop", frontal_only, without));
  // Two more views (sqrt(2) and 2), after the others, with more keypoints.
  ASSERT_EQ(models[0].views.size(), without.views.size() + 2);
  EXPECT_NEAR(models[0].views.back().scale, 2.0, 1e-3);
  EXPECT_GT(models[0].keypoints.size(), without.keypoints.size());
  QualityReport quality;
  ASSERT_TRUE(measure_quality(models, {crop}, params, {}, quality));
  Bytes bytes;
  ASSERT_TRUE(serialize_index(models, params, bytes, &quality));
  AlignedBytes buffer(bytes);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(index.params().views.max_scale, 2.f);
  const ModelQuality mq = index.model_quality(0);
  ASSERT_EQ(mq.view_count, models[0].views.size());
  EXPECT_NEAR(index.view_quality(mq.view_begin + mq.view_count - 1).scale, 2.f, 1e-3f);
}

// The small corpus with look-alike pairs written in (the writer takes any
// valid report), so that the look-alikes section has bytes to damage.
Bytes with_look_alikes(const std::vector<LookAlike>& pairs) {
  QualityReport q = small_corpus().small_quality;
  q.look_alikes = pairs;
  Bytes b;
  EXPECT_TRUE(serialize_index(small_corpus().small_models, corpus().params, b, &q));
  return b;
}

TEST_F(ModelIndexTest, RejectsBadQualitySections) {
  using namespace format;
  const Bytes good = with_look_alikes({{0, 1}, {1, 0}});
  ASSERT_TRUE(try_view(good));
  const std::size_t mq = section_offset(good, kSectionModelQuality);
  const std::size_t vq = section_offset(good, kSectionViewQuality);
  const std::size_t la = section_offset(good, kSectionLookAlikes);
  const std::size_t second = mq + kModelQualitySize;
  auto damaged = [&](auto&& change) {
    Bytes b = good;
    change(b);
    reseal(b);
    return b;
  };
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + second + kMqViewBegin,
                                              load<std::uint32_t>(b.data() + second) + 1);
                       }),
                       "model quality 1: view range not contiguous"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + second + kMqViewCount, 0xFFFFFFFFu);
                       }),
                       "model quality 1: view range out of bounds"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + second + kMqViewCount,
                                              load<std::uint32_t>(b.data() + second + 4) - 1);
                       }),
                       "view ranges do not cover all view records"));
  EXPECT_TRUE(rejected(
      damaged([&](Bytes& b) { store<std::uint32_t>(b.data() + mq + kMqSharedArcs, 0xFFFFFFF0u); }),
      "model quality 0: more shared arcs than arcs"));
  for (const float size : {std::nanf(""), -1.f, std::numeric_limits<float>::infinity()}) {
    EXPECT_TRUE(
        rejected(damaged([&](Bytes& b) { store<float>(b.data() + mq + kMqSmallestSize, size); }),
                 "model quality 0: bad size"));
    EXPECT_TRUE(
        rejected(damaged([&](Bytes& b) { store<float>(b.data() + second + kMqSceneSize, size); }),
                 "model quality 1: bad size"));
  }
  EXPECT_TRUE(
      rejected(damaged([&](Bytes& b) { store<std::uint32_t>(b.data() + mq + kMqFlags, 2); }),
               "unknown flags or reserved bytes set"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) { b[mq + kMqReserved + 7] = 1; }),
                       "unknown flags or reserved bytes set"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) { store<float>(b.data() + vq + kVqScale, 0.f); }),
                       "view quality 0: bad scale, tilt or longitude"));
  // Larger than the model image, in an index without such views (6.7).
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) { store<float>(b.data() + vq + kVqScale, 1.5f); }),
                       "view quality 0: bad scale, tilt or longitude"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) { store<float>(b.data() + vq + kVqTilt, 0.5f); }),
                       "view quality 0: bad scale, tilt or longitude"));
  EXPECT_TRUE(
      rejected(damaged([&](Bytes& b) { store<float>(b.data() + vq + kVqLongitude, 180.f); }),
               "view quality 0: bad scale, tilt or longitude"));
  EXPECT_TRUE(
      rejected(damaged([&](Bytes& b) { store<std::uint32_t>(b.data() + la, 2); }),  // 2 models
               "look-alike 0: model ids 2, 1 invalid"));
  EXPECT_TRUE(
      rejected(damaged([&](Bytes& b) { store<std::uint32_t>(b.data() + la + 4, 0); }),  // itself
               "look-alike 0: model ids 0, 0 invalid"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + la + kLookAlikeSize, 0);
                         store<std::uint32_t>(b.data() + la + kLookAlikeSize + 4, 1);
                       }),
                       "look-alike 1: pairs not sorted or repeated"));
  // Counts against sizes and against the models.
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         const std::size_t e = entry(b, kSectionModelQuality);
                         store<std::uint32_t>(b.data() + e + kEntCount, 1);
                         store<std::uint64_t>(b.data() + e + kEntSize, kModelQualitySize);
                       }),
                       "model quality section: count 1, expected 2"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         const std::size_t e = entry(b, kSectionModelQuality);
                         store<std::uint32_t>(b.data() + e + kEntCount, 0);
                         store<std::uint64_t>(b.data() + e + kEntSize, 0);
                       }),
                       "not empty without model quality"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + entry(b, kSectionLookAlikes) + kEntCount,
                                              3);
                       }),
                       "look-alikes section: size 16 does not match count 3"));
  // A 6.1 file must have the three sections; a 6.0 file has none and loads
  // without a report.
  Bytes renamed = good;
  store<std::uint32_t>(renamed.data() + entry(renamed, kSectionViewQuality) + kEntId, 99);
  fix_header_crc(renamed);
  EXPECT_TRUE(rejected(renamed, "view quality section missing"));
  Bytes older = good;
  for (std::uint32_t id : {kSectionModelQuality, kSectionViewQuality, kSectionLookAlikes})
    store<std::uint32_t>(older.data() + entry(older, id) + kEntId, 90 + id);
  store<std::uint16_t>(older.data() + kOffMinor, 0);
  fix_header_crc(older);
  AlignedBytes buffer(older);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_FALSE(index.has_quality());
  EXPECT_EQ(index.version_minor(), 0);
  // A flipped byte in each quality section fails its checksum.
  for (std::uint32_t id : {kSectionModelQuality, kSectionViewQuality, kSectionLookAlikes}) {
    Bytes b = good;
    b[section_offset(b, id) + section_size(b, id) - 1] ^= 0x40;
    EXPECT_TRUE(rejected(b, std::string(section_name(id)) + " section: checksum mismatch"));
  }
}

TEST_F(ModelIndexTest, SerializeRejectsBadQualityReport) {
  const std::vector<BuiltModel>& small = small_corpus().small_models;
  Bytes b;
  QualityReport q = small_corpus().small_quality;
  q.models.pop_back();
  EXPECT_FALSE(serialize_index(small, corpus().params, b, &q));
  q = small_corpus().small_quality;
  q.look_alikes = {{1, 1}};
  EXPECT_FALSE(serialize_index(small, corpus().params, b, &q));
  q.look_alikes = {{1, 0}, {0, 1}};  // not sorted
  EXPECT_FALSE(serialize_index(small, corpus().params, b, &q));
  q = small_corpus().small_quality;
  q.views.pop_back();
  EXPECT_FALSE(serialize_index(small, corpus().params, b, &q));
}

// --- Model appearance (format 6.2, sections 15-16) ------------------------

// What ModelAppearance documents, computed without OpenCV: the mean of the
// model pixels that appearance pixel (u, v) covers, [u / scale, (u + 1) /
// scale) x [v / scale, (v + 1) / scale), each weighted by its area inside
// that cell (cut at the image's edge).
double covered_mean(const cv::Mat& gray, double scale, int u, int v) {
  const double x0 = u / scale, x1 = (u + 1) / scale, y0 = v / scale, y1 = (v + 1) / scale;
  double sum = 0.0, area = 0.0;
  for (int y = static_cast<int>(y0); y < std::min<double>(y1, gray.rows); ++y) {
    const double wy = std::min(y + 1.0, y1) - std::max<double>(y, y0);
    for (int x = static_cast<int>(x0); x < std::min<double>(x1, gray.cols); ++x) {
      const double w = wy * (std::min(x + 1.0, x1) - std::max<double>(x, x0));
      sum += w * gray.at<std::uint8_t>(y, x);
      area += w;
    }
  }
  return sum / area;
}

// Checks a stored appearance against the model image: its size and scale
// for a long edge of `size` px, its pixels against an independent
// cv::resize (INTER_AREA, the same factor on both axes) and against
// covered_mean(), both within one grey level.
void expect_appearance_of(const ModelAppearance& look, const cv::Mat& gray, int size) {
  ASSERT_FALSE(look.empty());
  const int long_edge = std::max(gray.cols, gray.rows);
  const double factor = long_edge > size ? static_cast<double>(size) / long_edge : 1.0;
  EXPECT_EQ(look.scale, static_cast<float>(factor));
  EXPECT_EQ(std::max(look.width, look.height), std::min(size, long_edge));
  EXPECT_EQ(look.width, static_cast<int>(std::lround(gray.cols * factor)));
  EXPECT_EQ(look.height, static_cast<int>(std::lround(gray.rows * factor)));
  cv::Mat resized;
  cv::resize(gray, resized, cv::Size(), factor, factor, cv::INTER_AREA);
  ASSERT_EQ(resized.cols, look.width);
  ASSERT_EQ(resized.rows, look.height);
  int worst_resize = 0;
  double worst_mean = 0.0;
  for (int v = 0; v < look.height; ++v) {
    for (int u = 0; u < look.width; ++u) {
      const int stored = look.pixels[static_cast<std::size_t>(v) * look.width + u];
      worst_resize = std::max(worst_resize, std::abs(stored - resized.at<std::uint8_t>(v, u)));
      worst_mean = std::max(worst_mean, std::fabs(stored - covered_mean(gray, factor, u, v)));
    }
  }
  EXPECT_LE(worst_resize, 1) << "against cv::resize";
  EXPECT_LE(worst_mean, 1.0) << "against the mean of the covered model pixels";
}

TEST_F(ModelIndexTest, AppearanceIsTheAreaAveragedModelImage) {
  AlignedBytes buffer(bytes());
  ModelIndex index;
  ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
  ASSERT_EQ(index.params().views.appearance_size, 128);  // the default
  ASSERT_TRUE(index.has_appearance());
  // box.png, 324x223: 128x88 at 128 / 324.
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  const ModelAppearance look = index.appearance(0);
  EXPECT_EQ(look.width, 128);
  EXPECT_EQ(look.height, 88);
  EXPECT_EQ(look.scale, 128.f / 324.f);
  expect_appearance_of(look, box, 128);
  // The 200x200 crop of graf1.png: 128x128 at 0.64.
  const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
  expect_appearance_of(index.appearance(1), graf(cv::Rect(300, 220, 200, 200)).clone(), 128);
  EXPECT_EQ(index.max_appearance_pixels(), 128 * 128);
  // The pixels of the two models are consecutive in the pixel section.
  EXPECT_EQ(index.appearance(1).pixels, look.pixels + 128 * 88);
  EXPECT_EQ(index.appearance(1).pixels + 128 * 128, index.data() + index.byte_size());
  EXPECT_TRUE(index.appearance(-1).empty());
  EXPECT_TRUE(index.appearance(2).empty());
}

TEST(Appearance, SmallModelsKeepTheirSizeAndTallOnesScaleByTheirHeight) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty());
  Params params = paper_params();
  // Smaller than the appearance size: its own pixels at scale 1.
  const cv::Mat crop = box(cv::Rect(100, 50, 96, 96)).clone();
  BuiltModel small;
  ASSERT_TRUE(build_model(crop, "crop", params, small));
  // Taller than wide (box.png transposed, 223x324): the long edge is the
  // height, and scale = 128 / 324 on both axes (not width / model width).
  cv::Mat tall;
  cv::transpose(box, tall);
  BuiltModel portrait;
  ASSERT_TRUE(build_model(tall, "tall", params, portrait));
  // A smaller appearance size: 64 px.
  params.views.appearance_size = 64;
  BuiltModel box64;
  ASSERT_TRUE(build_model(box, "box64", params, box64));

  struct Case {
    const BuiltModel* model;
    const cv::Mat* image;
    int size;
  };
  for (const Case& c :
       {Case{&small, &crop, 128}, Case{&portrait, &tall, 128}, Case{&box64, &box, 64}}) {
    const BuiltModel* model = c.model;
    const cv::Mat* image = c.image;
    const int size = c.size;
    SCOPED_TRACE(model->name);
    Params p = paper_params();
    p.views.appearance_size = size;
    Bytes b;
    ASSERT_TRUE(serialize_index(std::vector<BuiltModel>{*model}, p, b));
    AlignedBytes buffer(b);
    ModelIndex index;
    const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
    ASSERT_TRUE(s) << s.message();
    expect_appearance_of(index.appearance(0), *image, size);
    EXPECT_EQ(index.max_appearance_pixels(),
              index.appearance(0).width * index.appearance(0).height);
  }
  EXPECT_EQ(small.appearance_scale, 1.f);
  EXPECT_EQ(0, cv::norm(small.appearance, crop, cv::NORM_INF));
  EXPECT_EQ(portrait.appearance.cols, 88);
  EXPECT_EQ(portrait.appearance.rows, 128);
  EXPECT_EQ(box64.appearance.cols, 64);
  EXPECT_EQ(box64.appearance.rows, 44);
}

TEST(Appearance, NoneStoredWithAppearanceSizeZero) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty());
  Params params = paper_params();
  params.views.appearance_size = 0;
  BuiltModel model;
  ASSERT_TRUE(build_model(box(cv::Rect(100, 50, 96, 96)).clone(), "crop", params, model));
  EXPECT_TRUE(model.appearance.empty());
  Bytes b;
  ASSERT_TRUE(serialize_index({model}, params, b));
  // Both sections are there (required from 6.2 on), empty.
  EXPECT_EQ(section_size(b, format::kSectionAppearances), 0u);
  EXPECT_EQ(section_size(b, format::kSectionAppearancePixels), 0u);
  AlignedBytes buffer(b);
  ModelIndex index;
  ASSERT_TRUE(ModelIndex::view(buffer.data(), buffer.size(), index));
  EXPECT_FALSE(index.has_appearance());
  EXPECT_TRUE(index.appearance(0).empty());
  EXPECT_EQ(index.max_appearance_pixels(), 0);
}

// keygraph eval's in-memory indexes go through the same writer.
TEST_F(ModelIndexTest, InMemoryIndexCarriesTheAppearances) {
  InMemoryIndex eval;
  const Status s = eval.build(models(), paper_params());
  ASSERT_TRUE(s) << s.message();
  ASSERT_TRUE(eval.index().has_appearance());
  expect_matches(eval.index(), models());
  EXPECT_EQ(eval.index().max_appearance_pixels(), 128 * 128);
}

TEST_F(ModelIndexTest, SerializeRejectsMissingOrMismatchedAppearance) {
  Bytes b;
  Params p = paper_params();
  p.views.appearance_size = 64;  // the models were built at 128
  Status s = serialize_index(models(), p, b);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("box: no appearance of 64 px"), std::string::npos) << s.message();
  std::vector<BuiltModel> without = models();
  without[1].appearance.release();
  s = serialize_index(without, paper_params(), b);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message().find("graf1_crop: no appearance"), std::string::npos) << s.message();
}

TEST_F(ModelIndexTest, RejectsBadAppearanceSections) {
  using namespace format;
  const Bytes& good = bytes();  // box.png 128x88, then graf1 crop 128x128
  const std::size_t first = section_offset(good, kSectionAppearances);
  const std::size_t second = first + kAppearanceSize;
  ASSERT_EQ(load<std::uint32_t>(good.data() + second + kApFirstPixel), 128u * 88u);
  auto damaged = [&](auto&& change) {
    Bytes b = good;
    change(b);
    reseal(b);
    return b;
  };
  auto set_u32 = [&](std::size_t at, std::uint32_t v) {
    return damaged([&](Bytes& b) { store<std::uint32_t>(b.data() + at, v); });
  };
  EXPECT_TRUE(rejected(set_u32(first + kApWidth, 129),
                       "model appearance 0: size 129x88 not within 1..128"));
  EXPECT_TRUE(rejected(set_u32(first + kApWidth, 0), "model appearance 0: size 0x88 not within"));
  EXPECT_TRUE(rejected(set_u32(second + kApHeight, 0xFFFFFFFFu),
                       "model appearance 1: size 128x4294967295 not within"));
  for (const float scale :
       {0.f, -0.5f, 1.5f, std::nanf(""), std::numeric_limits<float>::infinity()})
    EXPECT_TRUE(
        rejected(damaged([&](Bytes& b) { store<float>(b.data() + second + kApScale, scale); }),
                 "model appearance 1: scale not in (0, 1]"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) { store<float>(b.data() + first + kApScale, 0.5f); }),
                       "model appearance 0: size 128x88 is not the model's size times the scale"));
  // 127 px at 127 / 324 would be a consistent resampling, but not to 128 px.
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + first + kApWidth, 127);
                         store<float>(b.data() + first + kApScale, 127.f / 324.f);
                       }),
                       "model appearance 0: downsampled, but its long edge is not"));
  EXPECT_TRUE(rejected(set_u32(first + kApFirstPixel, 1),
                       "model appearance 0: pixel range not "
                       "contiguous"));
  EXPECT_TRUE(rejected(set_u32(second + kApFirstPixel, 128 * 88 - 1),
                       "model appearance 1: pixel range not contiguous"));
  // Fewer pixels than the records cover, and more.
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         const std::size_t e = entry(b, kSectionAppearancePixels);
                         store<std::uint32_t>(b.data() + e + kEntCount, 128 * 88 + 128 * 127);
                         store<std::uint64_t>(b.data() + e + kEntSize, 128 * 88 + 128 * 127);
                       }),
                       "model appearance 1: pixel range out of bounds"));
  EXPECT_TRUE(rejected(set_u32(second + kApHeight, 127),
                       "appearance pixels section: 27648 pixels, the appearances cover 27520"));
  // Counts against sizes, the models and the parameter.
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         store<std::uint32_t>(b.data() + entry(b, kSectionAppearances) + kEntCount,
                                              3);
                       }),
                       "model appearance section: size 32 does not match count 3 x 16 bytes"));
  EXPECT_TRUE(rejected(damaged([&](Bytes& b) {
                         const std::size_t e = entry(b, kSectionAppearances);
                         store<std::uint32_t>(b.data() + e + kEntCount, 1);
                         store<std::uint64_t>(b.data() + e + kEntSize, kAppearanceSize);
                       }),
                       "model appearance section: count 1, expected 2"));
  Params none = paper_params();
  none.views.appearance_size = 0;
  Bytes b = good;
  put_params(b, none);
  EXPECT_TRUE(rejected(b, "model appearance section: count 2, expected 0"));
  // Sections missing: one of the two (in a 6.2 file, or in an older one
  // that names either), or both in a 6.2 file.
  auto renamed = [&](std::initializer_list<std::uint32_t> ids, std::uint16_t minor) {
    Bytes r = good;
    for (std::uint32_t id : ids) store<std::uint32_t>(r.data() + entry(r, id) + kEntId, 90 + id);
    store<std::uint16_t>(r.data() + kOffMinor, minor);
    fix_header_crc(r);
    return r;
  };
  EXPECT_TRUE(
      rejected(renamed({kSectionAppearancePixels}, 2), "appearance pixels section missing"));
  EXPECT_TRUE(rejected(renamed({kSectionAppearancePixels}, 1), "one without the other"));
  EXPECT_TRUE(rejected(renamed({kSectionAppearances, kSectionAppearancePixels}, 2),
                       "model appearance section missing"));
  // A 6.1 file has neither, and zeros for the new parameters: it loads
  // without appearances; with an appearance size it is inconsistent.
  Bytes older = renamed({kSectionAppearances, kSectionAppearancePixels}, 1);
  EXPECT_TRUE(rejected(older, "model appearance section: count 0, expected 2"));
  put_params(older, none);
  AlignedBytes buffer(older);
  ModelIndex index;
  const Status s = ModelIndex::view(buffer.data(), buffer.size(), index);
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(index.version_minor(), 1);
  EXPECT_FALSE(index.has_appearance());
  EXPECT_EQ(index.max_appearance_pixels(), 0);
}

}  // namespace
}  // namespace kg
