// JSON for the tools' inputs (manifests, models.json), parsed strictly and
// within bounds: nesting at most kMaxJsonDepth levels (checked before the
// parser builds anything: a line of 50 MB of '[' would otherwise take
// gigabytes), and no key twice in one object (nlohmann keeps the last one
// silently). OpenCV-free: the fuzz targets compile it in.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace kg {

inline constexpr int kMaxJsonDepth = 16;

// On failure `error` says what is wrong ("not valid JSON", "duplicate key
// \"roi\"", "nested more than 16 levels deep"), without a location.
bool parse_json_strict(std::string_view text, nlohmann::json& out, std::string& error);

// Whether `text` holds a control character (a newline, NUL, ...): refused
// in names and paths from input files, which end up in error lines and
// file names.
bool has_control_character(std::string_view text);

}  // namespace kg
