#include "cli/device/detect_settings.h"

#include <string_view>

namespace kg::cli {

namespace {

// "NAME=VALUE" split; false without a name or an '='.
bool split(const std::string& assignment, std::string_view& name, std::string_view& value) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) return false;
  name = std::string_view(assignment).substr(0, eq);
  value = std::string_view(assignment).substr(eq + 1);
  return true;
}

std::string names_for_help() {
  std::string text;
  for (const std::string& n : detect_option_names()) text += (text.empty() ? "" : ", ") + n;
  return text;
}

}  // namespace

void DetectSettings::declare(Options& options) {
  options.value(
      "--set", "NAME=VALUE",
      "a runtime option of the detector over the index's own, repeatable: " + names_for_help() +
          " (the other parameters are fixed by the index: rebuild it to change them)",
      [this](const std::string& v) -> std::string {
        std::string_view name, value;
        if (!split(v, name, value)) return "takes NAME=VALUE";
        DetectOptions scratch;
        if (Status s = set_detect_option(scratch, name, value); !s) return s.message();
        assignments_.push_back(v);
        return {};
      });
}

Status DetectSettings::options_for(const ModelIndex& index, DetectOptions& out) const {
  out = DetectOptions::from(index);
  for (const std::string& a : assignments_) {
    std::string_view name, value;
    split(a, name, value);
    if (Status s = set_detect_option(out, name, value); !s) return s;
  }
  if (Status s = Detector::check_options(index, out); !s)
    return {StatusCode::kInvalidArgument, "--set: " + s.message()};
  return Status::ok();
}

}  // namespace kg::cli
