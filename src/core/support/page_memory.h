#pragma once

#include <cstddef>

namespace kg {

// Large, long-lived blocks (a detector's workspace) straight from the
// operating system where it has anonymous mappings: the block's pages go
// back to the system when it is released. From the heap instead, a process
// that rebuilds its detector (keygraph live reloading its index) grew by a
// workspace per rebuild: glibc raises its mmap threshold after the first
// large free, later workspaces come from the heap, and small allocations
// made between rebuilds split the freed blocks (tests/cli/soak_live.py).
// Aligned to at least 64 bytes; nullptr when out of memory.
void* allocate_pages(std::size_t bytes);
// `bytes` as given to allocate_pages.
void release_pages(void* block, std::size_t bytes);

}  // namespace kg
