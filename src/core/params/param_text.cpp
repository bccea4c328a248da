#include "keygraph/param_text.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>

#include "core/index/index_format.h"
#include "core/params/param_names.h"

namespace kg {
namespace {

// The whole text as a number of type T (no exceptions: the core is built
// without them). Floating-point text as strtod reads it ("1e-3", "inf" and
// "nan" parse; the range checks refuse what is out of range).
template <class T>
bool parse_number(std::string_view text, T& out) {
  if (text.empty()) return false;
  if constexpr (std::is_floating_point_v<T>) {
    const std::string copy(text);  // strtod needs a terminated string
    char* end = nullptr;
    const double v = std::strtod(copy.c_str(), &end);
    if (end != copy.c_str() + copy.size()) return false;
    out = static_cast<T>(v);
    return true;
  } else {
    T v{};
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size()) return false;
    out = v;
    return true;
  }
}

}  // namespace

Status set_param(Params& params, std::string_view name, std::string_view value) {
  bool known = false, parsed = false;
  format::visit_params(params, [&](const char* field_name, auto& field) {
    if (known || name != field_name) return;
    known = true;
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_enum_v<T>) {
      parsed = parse_enum(std::string(value).c_str(), field);
    } else {
      parsed = parse_number(value, field);
    }
  });
  if (!known)
    return {StatusCode::kInvalidArgument, "unknown parameter '" + std::string(name) + "'"};
  if (!parsed)
    return {StatusCode::kInvalidArgument,
            "bad value '" + std::string(value) + "' for " + std::string(name)};
  return Status::ok();
}

Status set_param(Params& params, std::string_view assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string_view::npos || eq == 0)
    return {StatusCode::kInvalidArgument,
            "--set takes NAME=VALUE, got '" + std::string(assignment) + "'"};
  return set_param(params, assignment.substr(0, eq), assignment.substr(eq + 1));
}

bool param_value_text(const Params& params, std::string_view name, std::string& out) {
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

Status preset_params(std::string_view name, Params& out) {
  if (name == "defaults") {
    out = Params{};
  } else if (name == "frontal") {
    out = frontal_params();
  } else if (name == "angled") {
    out = angled_params();
  } else {
    return {StatusCode::kInvalidArgument,
            "unknown preset '" + std::string(name) + "' (defaults, frontal or angled)"};
  }
  return Status::ok();
}

std::vector<std::string> preset_names() {
  return {"defaults", "frontal", "angled"};
}

}  // namespace kg
