// keygraph inspect: its options are the Options table below (keygraph inspect --help).
// Prints the header, every parameter, the section table with each section's
// checksum verified, per-model counts, sizes and appearance sizes, the
// stored appearance, the bytes per arc, and the model quality report
// (cli/device/quality_report.h).
// A file the reader rejects exits 1 with the reader's message on one stderr
// line (after the header and table, when those could be read, so that the
// damaged section shows as "crc BAD").
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "cli/device/device_commands.h"
#include "cli/device/options.h"
#include "cli/device/quality_report.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "core/params/param_names.h"
#include "core/selection/selection.h"
#include "keygraph/model_index.h"
#include "platform/files/regular_file.h"

namespace kg::cli {

namespace {

using namespace format;

// The most of a damaged file read to show its layout.
constexpr std::size_t kMaxRawBytes = std::size_t{1} << 30;

template <class E, class = std::enable_if_t<std::is_enum_v<E>>>
std::string value_text(E v) {
  const char* name = enum_name(v);
  return name != nullptr ? name : std::to_string(static_cast<int>(v));
}
// The shortest of %.Ng (N from `digits` up to `max_digits`) that reads back
// as the same value.
template <class T>
std::string shortest(T v, int digits, int max_digits) {
  char buf[40];
  for (; digits < max_digits; ++digits) {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, static_cast<double>(v));
    if (static_cast<T>(std::strtod(buf, nullptr)) == v) return buf;
  }
  std::snprintf(buf, sizeof(buf), "%.*g", max_digits, static_cast<double>(v));
  return buf;
}
std::string value_text(float v) {
  return shortest(v, 6, 9);
}
std::string value_text(double v) {
  return shortest(v, 15, 17);
}
std::string value_text(int v) {
  return std::to_string(v);
}
std::string value_text(std::uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "0x%016" PRIx64, v);
  return buf;
}

// Header and section table straight from the bytes, each section's CRC
// checked: what can be shown of a file before (or without) validation.
// Returns false when not even that can be read.
bool print_layout(const std::vector<std::uint8_t>& b) {
  const std::size_t n = b.size();
  if (n < kHeaderSize || std::memcmp(b.data(), kMagic, sizeof(kMagic)) != 0) return false;
  const std::uint8_t* d = b.data();
  const auto table_offset = load<std::uint32_t>(d + kOffTableOffset);
  const auto section_count = load<std::uint32_t>(d + kOffSectionCount);
  const std::uint64_t table_end =
      static_cast<std::uint64_t>(table_offset) + std::uint64_t{section_count} * kSectionEntrySize;
  if (section_count > 64 || table_offset < kHeaderSize || table_end > n) return false;
  std::uint8_t zero[4] = {0, 0, 0, 0};
  std::uint32_t crc = crc32(d, kOffHeaderCrc);
  crc = crc32(zero, 4, crc);
  crc = crc32(d + kOffHeaderCrc + 4, static_cast<std::size_t>(table_end) - kOffHeaderCrc - 4, crc);
  const auto major = load<std::uint16_t>(d + kOffMajor);
  std::printf("format %u.%u, %zu bytes (header says %" PRIu64 "), header crc %s\n", major,
              load<std::uint16_t>(d + kOffMinor), n, load<std::uint64_t>(d + kOffFileSize),
              crc == load<std::uint32_t>(d + kOffHeaderCrc) ? "ok" : "BAD");
  std::printf("parameter block at %u, %u bytes; section table at %u, %u sections\n",
              load<std::uint32_t>(d + kOffParamsOffset), load<std::uint32_t>(d + kOffParamsSize),
              table_offset, section_count);
  std::printf("\nsections:\n  %2s  %-18s %8s %10s %10s %8s  %s\n", "id", "name", "encoding",
              "offset", "size", "count", "crc");
  for (std::uint32_t i = 0; i < section_count; ++i) {
    const std::uint8_t* e = d + table_offset + std::size_t{i} * kSectionEntrySize;
    const auto id = load<std::uint32_t>(e + kEntId);
    const auto encoding = load<std::uint32_t>(e + kEntEncoding);
    const auto offset = load<std::uint64_t>(e + kEntOffset);
    const auto size = load<std::uint64_t>(e + kEntSize);
    const char* check = "out of bounds";
    if (offset <= n && size <= n - offset)
      check = crc32(d + offset, static_cast<std::size_t>(size)) == load<std::uint32_t>(e + kEntCrc)
                  ? "ok"
                  : "BAD";
    // Names and encodings as this version defines them.
    const char* name = major == kVersionMajor ? section_name(id) : "-";
    std::string enc = "-";
    if (major == kVersionMajor &&
        (id == kSectionDescriptors || id == kSectionTreeNodes || id == kSectionLeafBounds))
      enc = encoding <= 2 ? encoding_name(static_cast<DescriptorEncoding>(encoding))
                          : std::to_string(encoding);
    std::printf("  %2u  %-18s %8s %10" PRIu64 " %10" PRIu64 " %8u  crc %s\n", id, name, enc.c_str(),
                offset, size, load<std::uint32_t>(e + kEntCount), check);
  }
  return true;
}

void print_index(const ModelIndex& index) {
  std::printf("\nparameters:\n");
  visit_params(index.params(), [](const char* name, const auto& value) {
    std::printf("  %-34s %s\n", name, value_text(value).c_str());
  });

  const DescriptorEncoding encoding = index.descriptor_encoding();
  const double descriptor_bytes = static_cast<double>(encoded_point_size(encoding));
  const double node_bytes =
      static_cast<double>(index.tree_node_count()) * static_cast<double>(tree_node_size(encoding));
  // Two points per leaf (section 10).
  const double bound_bytes =
      2.0 * static_cast<double>(std::uint64_t{1} << index.tree_depth()) * descriptor_bytes;
  // A tree arc: u32 source (section 4) and i16 offset to its target (section 9).
  constexpr double kTreeArcBytes = 6.0;
  const double arcs = index.arc_count();
  const bool sift = index.vertex_descriptors() != nullptr;
  const double per_keypoint = 12.0 + (sift ? kVertexDescriptorSize : 0);  // position, scale
  std::printf(
      "\nmodels (bytes: record, name, keypoints%s, arcs with descriptors, share of the "
      "tree nodes and leaf bounds):\n",
      sift ? " with vertex descriptors" : "");
  std::printf("  %3s  %-20s %9s %9s %12s %12s %9s %11s\n", "#", "name", "keypoints", "arcs",
              "keygraphs", "bytes", "bytes/arc", "appearance");
  double appearance_bytes = 0.0;  // sections 15 and 16
  for (int m = 0; m < index.model_count(); ++m) {
    const ModelInfo info = index.model(m);
    const double bytes = static_cast<double>(kModelRecordSize + info.name.size()) +
                         per_keypoint * info.keypoint_count +
                         (kTreeArcBytes + descriptor_bytes) * info.arc_count +
                         (arcs > 0 ? (node_bytes + bound_bytes) * info.arc_count / arcs : 0.0);
    const ModelAppearance look = index.appearance(m);
    const std::string look_size =
        look.empty() ? "-" : std::to_string(look.width) + "x" + std::to_string(look.height);
    if (!look.empty())
      appearance_bytes +=
          static_cast<double>(kAppearanceSize) + double{1} * look.width * look.height;
    std::printf("  %3d  %-20.*s %9u %9u %12" PRIu64 " %12.0f %9.2f %11s\n", m,
                static_cast<int>(info.name.size()), info.name.data(), info.keypoint_count,
                info.arc_count, info.keygraph_count, bytes,
                info.arc_count > 0 ? bytes / info.arc_count : 0.0, look_size.c_str());
  }
  const double size = static_cast<double>(index.byte_size());
  std::printf(
      "\ntotal: %s, %u keypoints, %u arcs, %u tree nodes (depth %d), %s "
      "descriptors\n",
      counted(index.model_count(), "model").c_str(), index.keypoint_count(), index.arc_count(),
      index.tree_node_count(), index.tree_depth(), encoding_name(encoding));
  // The search's budget as the detector applies it (format 6.3 grows it
  // with the models).
  const int leaves = ArcSearch::leaves_for(index.params().descriptor,
                                           static_cast<std::uint64_t>(index.model_count()));
  if (leaves == 0) {
    std::printf("search: exact\n");
  } else {
    std::printf(
        "search: %d leaves per query (descriptor.max_search_leaves %d, grown beyond %d "
        "models: this index has %d)\n",
        leaves, index.params().descriptor.max_search_leaves,
        index.params().descriptor.search_reference_models, index.model_count());
  }
  if (index.has_appearance()) {
    std::printf("appearance: %d px long edge, %.1f KB\n", index.params().views.appearance_size,
                appearance_bytes / 1024.0);
  } else {
    std::printf("appearance: none (%s)\n", index.version_minor() < 2
                                               ? "format older than 6.2; rebuild the index"
                                               : "views.appearance_size is 0");
  }
  if (arcs > 0) {
    std::printf(
        "bytes per arc: %.2f (file %zu bytes / %u arcs): tree arcs %.0f, descriptors %.0f, "
        "tree nodes %.2f, leaf bounds %.2f, keypoints %.2f, appearance %.2f, the rest %.2f\n",
        size / arcs, index.byte_size(), index.arc_count(), kTreeArcBytes, descriptor_bytes,
        node_bytes / arcs, bound_bytes / arcs, per_keypoint * index.keypoint_count() / arcs,
        appearance_bytes / arcs,
        (size - node_bytes - bound_bytes - (kTreeArcBytes + descriptor_bytes) * arcs -
         per_keypoint * index.keypoint_count() - appearance_bytes) /
            arcs);
  }
}

}  // namespace

int cmd_inspect(const Args& args) {
  std::string path;
  Options options("inspect", "I.kgi",
                  "Prints an index's header, every parameter, the section table with each\n"
                  "section's checksum verified, the models, the bytes per arc and the model\n"
                  "quality report (docs/QUALITY.md).");
  options
      .positional("I.kgi", "the model index (one)",
                  [&path](const std::string& v) {
                    if (!path.empty()) return std::string("one index at a time");
                    path = v;
                    return std::string();
                  })
      .example("keygraph inspect signs.kgi");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (path.empty()) return options.usage_error("no index given (keygraph inspect I.kgi)");
  // Validation first, through the reader the detector uses (it also rejects
  // directories and missing files with a clear message).
  ModelIndex index;
  // Read into memory, never mapped: no SIGBUS if the file shrinks meanwhile.
  const Status status = ModelIndex::read(path, index);
  // The raw bytes of a file the reader could open (never a FIFO or device,
  // which it refuses), to show its layout even when it is damaged.
  std::vector<std::uint8_t> bytes;
  if (status || status.code() == StatusCode::kCorruptData ||
      status.code() == StatusCode::kUnsupportedVersion) {
    if (!platform::read_regular_file(path, bytes,
                                     index.byte_size() > 0 ? index.byte_size() : kMaxRawBytes))
      bytes.clear();
  }
  std::printf("index: %s\n", path.c_str());
  const bool shown = print_layout(bytes);
  std::fflush(stdout);
  if (!status) return fail(status.message());
  if (!shown) return fail(path + ": cannot read the section table");
  print_index(index);
  print_quality_report(index, true, stdout);
  return 0;
}

}  // namespace kg::cli
