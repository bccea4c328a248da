// Work spread over threads on the desktop side (model builds, test
// fixtures). The core never starts threads: an application decides where
// the detector runs.
#pragma once

#include <cstddef>
#include <functional>

#include "keygraph/status.h"

namespace kg {

// Threads to use for `count` items when `requested` are asked for: 0 means
// one per CPU the process may run on (its affinity mask: taskset, a
// container's cpuset); never more than the items, never fewer than 1.
int worker_count(int requested, std::size_t count);

// Calls work(i) for every i in [0, count), on up to worker_count(threads,
// count) threads (the caller's among them). Indices are handed out in
// increasing order; once a call returns false the threads stop taking
// indices (one taken just before may still run), and every index below a
// failed one has run. An exception thrown by `work` stops it the same way; after every
// thread has finished, the exception of the lowest index that threw is
// rethrown here.
void parallel_for(std::size_t count, int threads, const std::function<bool(std::size_t)>& work);

// parallel_for() over work that can fail: a failed Status stops it as
// `false` does, and the first failure in index order is returned (every
// index below it has run), the same one for any thread count.
Status parallel_for_status(std::size_t count, int threads,
                           const std::function<Status(std::size_t)>& work);

}  // namespace kg
