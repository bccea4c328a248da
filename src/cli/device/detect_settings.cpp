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

std::string option_names() {
  std::string text;
  for (const std::string& n : detect_option_names()) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// The most threads a detector takes (Limits::threads).
constexpr int kMaxThreads = 64;

}  // namespace

std::string DetectSettings::add(const std::string& assignment) {
  std::string_view name, value;
  if (!split(assignment, name, value))
    return "--set " + assignment + ": takes NAME=VALUE (runtime options: " + option_names() + ")";
  DetectOptions scratch;
  if (Status s = set_detect_option(scratch, name, value); !s) {
    const bool known = s.message().rfind("unknown option", 0) != 0;
    return "--set " + assignment + ": " + s.message() +
           (known ? "" : " (runtime options: " + option_names() + ")");
  }
  assignments_.push_back(assignment);
  return {};
}

void DetectSettings::declare(Options& options) {
  options
      .value("--set", "NAME=VALUE",
             "a runtime option of the detector over the index's own: " + option_names() +
                 " (the other parameters are fixed by the index: rebuild it to change them)",
             [this](const std::string& v) { return add(v); })
      .repeatable();
  declare_threads(options);
}

void DetectSettings::declare_threads(Options& options) {
  options.integer("--threads", "N", threads_, 1, kMaxThreads,
                  "threads per detection, the caller's included (the detections are the same\n"
                  "for any count)");
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

Limits DetectSettings::limits(Limits base) const {
  base.threads = threads_;
  return base;
}

}  // namespace kg::cli
