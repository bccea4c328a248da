// --set NAME=VALUE and --threads N for the commands that detect with an
// index (detect, live, bench; eval's keygraph method): the detector's
// runtime options (keygraph/detector.h, DetectOptions), applied over the
// index's own, and its thread count (Limits::threads). A parameter the
// index fixes (keypoints, descriptors, views...) is refused with the
// reason: it needs a rebuilt index. `eval` builds its own indexes, so its
// --set takes every parameter and these only for the rest (add()).
#pragma once

#include <string>
#include <vector>

#include "cli/device/options.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"
#include "keygraph/status.h"

namespace kg::cli {

// The settings of one command line, checked for syntax while parsing.
class DetectSettings {
 public:
  // Declares --set on `options` (repeatable), its help listing the names,
  // and --threads.
  void declare(Options& options);
  // Declares --threads alone (eval's --set is its own).
  void declare_threads(Options& options);
  // Checks one "NAME=VALUE" and keeps it; returns an error message (naming
  // the runtime options when NAME is not one), or empty.
  std::string add(const std::string& assignment);
  // The index's options with the settings applied, checked against the
  // index (Detector::set_options's rules); kInvalidArgument names the
  // setting at fault.
  Status options_for(const ModelIndex& index, DetectOptions& out) const;
  // `base` with the thread count of --threads.
  Limits limits(Limits base = Limits{}) const;
  bool empty() const { return assignments_.empty(); }
  int threads() const { return threads_; }

 private:
  std::vector<std::string> assignments_;
  int threads_ = 1;
};

}  // namespace kg::cli
