// How the evaluation's keygraph detectors run (keygraph eval --threads, and
// --set of the runtime options an index does not store): over each index's
// own options (DesktopDetector applies them).
#pragma once

#include <string>
#include <vector>

namespace kg {

struct DetectorSettings {
  int threads = 1;  // Limits::threads
  // "NAME=VALUE" runtime options (keygraph/detector.h, set_detect_option()),
  // applied in order.
  std::vector<std::string> options;
};

}  // namespace kg
