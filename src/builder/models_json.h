// The models.json of `keygraph eval --truth --models` (docs/EVAL.md): an
// object mapping model names to image files, each either "file.png" or
// {"file": "file.png", "roi": [x, y, width, height]}. OpenCV-free (the
// fuzz target compiles it in); builder/model_set.h reads the file and
// resolves the paths.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace kg {

// Bounds of a models.json (docs/EVAL.md): its size, and its entries (also
// the most models one build or evaluation takes: model_set.h).
inline constexpr std::size_t kMaxModelsJsonBytes = std::size_t{16} << 20;
inline constexpr int kMaxModels = 4096;

struct ModelEntry {
  std::string name;
  std::string file;  // as written (relative to the models.json)
  bool has_roi = false;
  int roi[4] = {0, 0, 0, 0};  // x, y, width, height: x, y >= 0, width, height >= 1
};

// Parses the text of a models.json. Strict: valid JSON (strict_json.h: no
// key twice, bounded nesting), an object of 1..kMaxModels entries, names
// without control characters, no field but "file" and "roi", an ROI of
// four whole numbers with its right and bottom edges within an int. On
// failure `error` says what is wrong (without the file's name).
bool parse_models_json(std::string_view text, std::vector<ModelEntry>& out, std::string& error);

}  // namespace kg
