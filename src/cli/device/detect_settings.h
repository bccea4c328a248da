// --set NAME=VALUE for the commands that detect with an index (detect,
// live, bench): the detector's runtime options (keygraph/detector.h,
// DetectOptions), applied over the index's own. A parameter the index fixes
// (keypoints, descriptors, views...) is refused with the reason: it needs a
// rebuilt index. `eval` builds its own indexes, so its --set takes every
// parameter.
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
  // Declares --set on `options` (repeatable), its help listing the names.
  void declare(Options& options);
  // The index's options with the settings applied, checked against the
  // index (Detector::set_options's rules); kInvalidArgument names the
  // setting at fault.
  Status options_for(const ModelIndex& index, DetectOptions& out) const;
  bool empty() const { return assignments_.empty(); }

 private:
  std::vector<std::string> assignments_;
};

}  // namespace kg::cli
