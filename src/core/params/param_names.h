// Names of the enumerated parameter values, as `--set NAME=VALUE`,
// `keygraph build` and `keygraph inspect` spell them: the one table both
// directions use.
#pragma once

#include <cstdint>
#include <cstring>

#include "keygraph/params.h"

namespace kg {

struct EnumName {
  std::uint8_t value;
  const char* name;
};

template <class E>
struct EnumNames;
template <>
struct EnumNames<KeypointDetector> {
  static constexpr EnumName values[] = {{0, "hessian"}, {1, "mser"}};
};
template <>
struct EnumNames<Structure> {
  static constexpr EnumName values[] = {{2, "2"}, {3, "3"}, {4, "4"}};
};
template <>
struct EnumNames<SceneSampling> {
  static constexpr EnumName values[] = {{0, "random"}, {1, "strongest"}};
};
template <>
struct EnumNames<VertexDescriptor> {
  static constexpr EnumName values[] = {{0, "none"}, {1, "sift"}};
};
template <>
struct EnumNames<DescriptorEncoding> {
  static constexpr EnumName values[] = {{0, "float32"}, {1, "int16"}, {2, "int8"}};
};

// The value's name, or nullptr for a value without one (a damaged index).
template <class E>
const char* enum_name(E v) {
  for (const EnumName& n : EnumNames<E>::values) {
    if (n.value == static_cast<std::uint8_t>(v)) return n.name;
  }
  return nullptr;
}

// The value named `text`; false (and `out` unchanged) for an unknown name.
template <class E>
bool parse_enum(const char* text, E& out) {
  for (const EnumName& n : EnumNames<E>::values) {
    if (std::strcmp(n.name, text) == 0) {
      out = static_cast<E>(n.value);
      return true;
    }
  }
  return false;
}

}  // namespace kg
