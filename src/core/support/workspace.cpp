#include "core/support/workspace.h"

#include <cstdio>
#include <cstdlib>

namespace kg {

void* Workspace::do_allocate(std::size_t bytes, std::size_t alignment) {
  const auto base = reinterpret_cast<std::uintptr_t>(base_);
  const std::size_t start = align_up(base + used_, alignment) - base;
  if (base_ == nullptr || start > size_ || bytes > size_ - start) {
    std::fprintf(stderr, "keygraph: internal error: workspace of %zu bytes exhausted\n", size_);
    std::abort();
  }
  used_ = start + bytes;
  return base_ + start;
}

void* MeasuringResource::do_allocate(std::size_t bytes, std::size_t alignment) {
  measured_ = align_up(measured_, alignment) + bytes;
  alignas(kWorkspaceAlignment) static std::uint8_t placeholder[kWorkspaceAlignment];
  return placeholder;
}

}  // namespace kg
