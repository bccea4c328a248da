// Work spread over threads on the desktop side (model builds, test
// fixtures). The core never starts threads: an application decides where
// the detector runs.
#pragma once

#include <cstddef>
#include <functional>

namespace kg {

// Threads to use for `count` items when `requested` are asked for: 0 means
// one per hardware thread; never more than the items, never fewer than 1.
int worker_count(int requested, std::size_t count);

// Calls work(i) for every i in [0, count), on up to worker_count(threads,
// count) threads (the caller's among them). Indices are handed out in
// increasing order; once a call returns false no further index is handed
// out (those already started finish), so every index below a failed one
// has run. An exception thrown by `work` stops the handing out as well and
// is rethrown here (the first one) after every thread has finished.
void parallel_for(std::size_t count, int threads, const std::function<bool(std::size_t)>& work);

}  // namespace kg
