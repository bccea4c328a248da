// Small bridges to parts of the core's API that are being reworked
// (workspace arena, fixed-capacity DetectionList), so the device commands
// compile against the core before and after the change.
#pragma once

#include <cstddef>
#include <optional>

#include "keygraph/detector.h"

namespace kg::cli {

// Reserves room for `n` detections when DetectionList grows (std::vector),
// so the first frames do not allocate in the result; a fixed-capacity list
// needs nothing.
template <class List>
void reserve_detections(List& list, int n) {
  if constexpr (requires { list.reserve(std::size_t{}); })
    list.reserve(static_cast<std::size_t>(n));
}

// Detector::workspace_bytes() when the core has it; nullopt until then.
// TODO(core): call detector.workspace_bytes() directly once it is in
// include/keygraph/detector.h.
template <class D>
std::optional<std::size_t> workspace_bytes(const D& detector) {
  if constexpr (requires { detector.workspace_bytes(); }) {
    return static_cast<std::size_t>(detector.workspace_bytes());
  } else {
    return std::nullopt;
  }
}

}  // namespace kg::cli
