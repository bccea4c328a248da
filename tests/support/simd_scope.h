// Runs a scope at one SIMD level (keygraph/simd.h) and restores the level
// that was in use, for tests comparing vector code with its reference.
#pragma once

#include "keygraph/simd.h"

namespace kg::test {

class SimdScope {
 public:
  explicit SimdScope(SimdLevel level) : saved_(simd_level()) { set_simd_level(level); }
  ~SimdScope() { set_simd_level(saved_); }
  SimdScope(const SimdScope&) = delete;
  SimdScope& operator=(const SimdScope&) = delete;

 private:
  SimdLevel saved_;
};

}  // namespace kg::test
