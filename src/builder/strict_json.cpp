#include "builder/strict_json.h"

#include <set>
#include <vector>

namespace kg {

namespace {

// The deepest nesting of arrays and objects, outside strings; stops
// counting past `limit`.
int nesting_depth(std::string_view text, int limit) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > deepest) deepest = depth;
      if (deepest > limit) break;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

bool parse_json_strict(std::string_view text, nlohmann::json& out, std::string& error) {
  using Json = nlohmann::json;
  if (nesting_depth(text, kMaxJsonDepth) > kMaxJsonDepth) {
    error = "nested more than " + std::to_string(kMaxJsonDepth) + " levels deep";
    return false;
  }
  std::vector<std::set<std::string>> keys;  // of each open object
  std::string duplicate;
  bool has_duplicate = false;
  const Json::parser_callback_t check_keys = [&](int, Json::parse_event_t event, Json& parsed) {
    if (event == Json::parse_event_t::object_start) {
      keys.emplace_back();
    } else if (event == Json::parse_event_t::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (event == Json::parse_event_t::key && !keys.empty() && parsed.is_string()) {
      const std::string& key = parsed.get_ref<const std::string&>();
      if (!keys.back().insert(key).second && !has_duplicate) {
        has_duplicate = true;
        duplicate = key;
      }
    }
    return true;
  };
  out = Json::parse(text.begin(), text.end(), check_keys, false);
  if (out.is_discarded()) {
    error = "not valid JSON";
    return false;
  }
  if (has_duplicate) {
    error = "duplicate key \"" + duplicate + "\"";
    return false;
  }
  return true;
}

bool has_control_character(std::string_view text) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return true;
  }
  return false;
}

}  // namespace kg
