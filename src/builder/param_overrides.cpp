#include "builder/param_overrides.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>

#include "core/index/index_format.h"
#include "core/index/param_names.h"

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

bool param_value_text(const Params& params, const std::string& name, std::string& out) {
  bool known = false;
  format::visit_params(params, [&](const char* field_name, const auto& field) {
    if (known || name != field_name) return;
    known = true;
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_enum_v<T>) {
      const char* text = enum_name(field);
      out = text != nullptr ? text : std::to_string(static_cast<int>(field));
    } else if constexpr (std::is_floating_point_v<T>) {
      // The shortest text that reads back as the same value.
      char buf[32];
      if (field == std::floor(field) && std::fabs(field) < 1e15) {
        std::snprintf(buf, sizeof(buf), "%.0f", static_cast<double>(field));
        out = buf;
        return;
      }
      for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(buf, sizeof(buf), "%.*g", digits, static_cast<double>(field));
        if (static_cast<T>(std::strtod(buf, nullptr)) == field) break;
      }
      out = buf;
    } else {
      out = std::to_string(field);
    }
  });
  return known;
}

std::vector<std::string> param_names() {
  std::vector<std::string> names;
  const Params params;
  format::visit_params(params, [&](const char* name, const auto&) { names.emplace_back(name); });
  return names;
}

Params angled_params(Params base) {
  base.views.max_tilt = 60.f;
  base.views.tilt_levels = 2;
  base.ransac.min_triangle_correlation = 0.6f;
  base.graph.complete_circuits = 1;
  base.graph.max_neighbour_rank = 0;
  base.descriptor.max_search_leaves = 10;
  return base;
}

Params frontal_params(Params base) {
  base.views.max_tilt = 0.f;
  base.views.tilt_levels = 0;
  base.ransac.min_triangle_correlation = 0.f;
  base.graph.complete_circuits = 0;
  base.graph.max_neighbour_rank = 0;
  base.descriptor.max_search_leaves = 20;
  return base;
}

}  // namespace kg
