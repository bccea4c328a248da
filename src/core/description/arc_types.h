// Arc descriptors and the search points of the model index's tree, in
// their float and quantised encodings (DescriptorParams::encoding). Internal
// to the core and the builder: the public API never shows them.
#pragma once

#include <array>
#include <cstdint>

#include "keygraph/types.h"

namespace kg {

// An arc descriptor has 2 * kMaxCoefficients numbers (keygraph/types.h):
// the real and imaginary parts of DFT coefficients 1..m.
inline constexpr int kDescriptorSize = 2 * kMaxCoefficients;
using ArcDescriptor = std::array<float, kDescriptorSize>;
// The same descriptor quantised for storage and search
// (DescriptorParams::encoding): each component times 32767 or 127, rounded.
using ArcDescriptorI16 = std::array<std::int16_t, kDescriptorSize>;
using ArcDescriptorI8 = std::array<std::int8_t, kDescriptorSize>;

// What the model index's search tree stores per arc: the descriptor, then
// the arc's scale attributes ln(length / sigma) at its start and at its end
// (core/description/arc_attributes.h), in the same encoding.
inline constexpr int kArcAttributes = 2;
inline constexpr int kSearchDims = kDescriptorSize + kArcAttributes;
using ArcSearchPoint = std::array<float, kSearchDims>;
using ArcSearchPointI16 = std::array<std::int16_t, kSearchDims>;
using ArcSearchPointI8 = std::array<std::int8_t, kSearchDims>;

}  // namespace kg
