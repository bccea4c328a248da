// libFuzzer target for the models.json reader of eval --truth
// (builder/models_json.h, docs/EVAL.md): each input is a file's text. What
// the parser accepts must keep its promises -- 1..kMaxModels entries, names
// non-empty, distinct and without control characters, a non-empty file
// name, an ROI of whole numbers whose right and bottom edges fit an int --
// and what it refuses must say why.
//
// Seeds: tests/fuzz/seeds/models_json/.
//   cmake --preset fuzz && cmake --build --preset fuzz --target fuzz_models_json
//   build/fuzz/tests/fuzz/fuzz_models_json CORPUS_DIR tests/fuzz/seeds/models_json \
//     -max_total_time=60
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "builder/models_json.h"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::vector<kg::ModelEntry> entries;
  std::string error;
  if (!kg::parse_models_json(text, entries, error)) {
    check(!error.empty() && entries.empty());
    return 0;
  }
  check(!entries.empty() && entries.size() <= static_cast<std::size_t>(kg::kMaxModels));
  std::set<std::string> names;
  for (const kg::ModelEntry& e : entries) {
    check(!e.name.empty() && !e.file.empty());
    check(names.insert(e.name).second);
    for (const char c : e.name) check(static_cast<unsigned char>(c) >= 0x20 && c != 0x7f);
    if (!e.has_roi) continue;
    check(e.roi[0] >= 0 && e.roi[1] >= 0 && e.roi[2] >= 1 && e.roi[3] >= 1);
    check(static_cast<long long>(e.roi[0]) + e.roi[2] <= INT_MAX);
    check(static_cast<long long>(e.roi[1]) + e.roi[3] <= INT_MAX);
  }
  return 0;
}
