#include "builder/models_json.h"

#include <algorithm>
#include <cstdint>
#include <limits>

#include "builder/strict_json.h"

namespace kg {

namespace {

using Json = nlohmann::json;

// [x, y, width, height]: whole numbers, x, y >= 0, width, height >= 1, and
// x + width, y + height within an int (a value of 2^32 must not wrap).
bool read_roi(const Json& r, int (&roi)[4]) {
  if (!r.is_array() || r.size() != 4) return false;
  std::int64_t v[4];
  for (std::size_t i = 0; i < 4; ++i) {
    if (r[i].is_number_unsigned()) {
      if (r[i].get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
        return false;
      v[i] = static_cast<std::int64_t>(r[i].get<std::uint64_t>());
    } else if (r[i].is_number_integer()) {
      v[i] = r[i].get<std::int64_t>();
    } else {
      return false;
    }
  }
  constexpr std::int64_t kMax = std::numeric_limits<int>::max();
  if (v[0] < 0 || v[1] < 0 || v[2] < 1 || v[3] < 1 || v[0] + v[2] > kMax || v[1] + v[3] > kMax)
    return false;
  for (int i = 0; i < 4; ++i) roi[i] = static_cast<int>(v[i]);
  return true;
}

}  // namespace

bool parse_models_json(std::string_view text, std::vector<ModelEntry>& out, std::string& error) {
  out.clear();
  Json doc;
  if (!parse_json_strict(text, doc, error)) return false;
  if (!doc.is_object() || doc.empty()) {
    error = "expected an object mapping model names to image files";
    return false;
  }
  if (doc.size() > static_cast<std::size_t>(kMaxModels)) {
    error = std::to_string(doc.size()) + " models, over the " + std::to_string(kMaxModels) +
            " a models.json may have";
    return false;
  }
  for (const auto& [name, value] : doc.items()) {
    const std::string where = "model \"" + name + "\": ";
    if (name.empty() || has_control_character(name)) {
      error = where + "a model name must be non-empty, without control characters";
      out.clear();
      return false;
    }
    ModelEntry entry;
    entry.name = name;
    const Json* file = &value;
    if (value.is_object()) {
      for (const auto& [key, field] : value.items()) {
        (void)field;
        if (key != "file" && key != "roi") {
          error = where + "unknown field \"" + key + "\" (a model takes \"file\" and \"roi\")";
          out.clear();
          return false;
        }
      }
      if (!value.contains("file")) {
        error = where + "no \"file\"";
        out.clear();
        return false;
      }
      file = &value["file"];
      if (value.contains("roi")) {
        if (!read_roi(value["roi"], entry.roi)) {
          error = where +
                  "\"roi\" must be [x, y, width, height] in pixels (whole numbers, x and y >= 0, "
                  "width and height >= 1)";
          out.clear();
          return false;
        }
        entry.has_roi = true;
      }
    }
    if (!file->is_string() || file->get<std::string>().empty()) {
      error = where + "expected an image file name";
      out.clear();
      return false;
    }
    entry.file = file->get<std::string>();
    out.push_back(std::move(entry));
  }
  return true;
}

}  // namespace kg
