#include "build/param_overrides.h"

#include <charconv>
#include <cstdint>
#include <string>
#include <type_traits>

#include "core/index_format.h"
#include "core/param_names.h"

namespace kg {
namespace {

template <class T>
bool parse_number(const std::string& text, T& out) {
  if constexpr (std::is_floating_point_v<T>) {
    try {
      std::size_t used = 0;
      const double v = std::stod(text, &used);
      if (used != text.size()) return false;
      out = static_cast<T>(v);
      return true;
    } catch (...) {
      return false;
    }
  } else {
    const auto r = std::from_chars(text.data(), text.data() + text.size(), out);
    return r.ec == std::errc() && r.ptr == text.data() + text.size();
  }
}

}  // namespace

Status apply_param_override(const std::string& assignment, Params& params) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    return {StatusCode::kInvalidArgument, "--set takes NAME=VALUE, got '" + assignment + "'"};
  const std::string name = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  bool known = false, parsed = false;
  format::visit_params(params, [&](const char* field_name, auto& field) {
    if (known || name != field_name) return;
    known = true;
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_enum_v<T>) {
      parsed = parse_enum(value.c_str(), field);
    } else {
      parsed = parse_number(value, field);
    }
  });
  if (!known) return {StatusCode::kInvalidArgument, "unknown parameter '" + name + "'"};
  if (!parsed) return {StatusCode::kInvalidArgument, "bad value '" + value + "' for " + name};
  return Status::ok();
}

std::vector<std::string> param_names() {
  std::vector<std::string> names;
  const Params params;
  format::visit_params(params, [&](const char* name, const auto&) { names.emplace_back(name); });
  return names;
}

}  // namespace kg
