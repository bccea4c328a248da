#include "builder/parallel.h"

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace kg {

namespace {

// CPUs this process may run on: its affinity mask (taskset, a container's
// cpuset), else what the hardware has.
unsigned available_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return static_cast<unsigned>(n);
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace

int worker_count(int requested, std::size_t count) {
  std::size_t n = requested > 0 ? static_cast<std::size_t>(requested) : available_cpus();
  n = std::min(n, count);
  return static_cast<int>(std::max<std::size_t>(1, n));
}

void parallel_for(std::size_t count, int threads, const std::function<bool(std::size_t)>& work) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex error_mutex;
  std::exception_ptr error;
  std::size_t error_index = std::numeric_limits<std::size_t>::max();
  auto run = [&] {
    while (!stop.load()) {
      // Once taken, an index runs even if a failure comes meanwhile: it may
      // lie below the failed one, which must all run.
      const std::size_t i = next.fetch_add(1);
      if (i >= count) return;
      try {
        if (!work(i)) stop = true;
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (i < error_index) {
          error = std::current_exception();
          error_index = i;
        }
        stop = true;
      }
    }
  };
  const int workers = worker_count(threads, count);
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(workers - 1));
  for (int t = 1; t < workers; ++t) {
    try {
      pool.emplace_back(run);
    } catch (...) {
      break;  // no more threads to be had: fewer workers do the same work
    }
  }
  run();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

Status parallel_for_status(std::size_t count, int threads,
                           const std::function<Status(std::size_t)>& work) {
  std::vector<Status> results(count);
  parallel_for(count, threads, [&](std::size_t i) {
    results[i] = work(i);
    return results[i].is_ok();
  });
  for (Status& s : results)
    if (!s) return std::move(s);
  return Status::ok();
}

}  // namespace kg
