// A fixed set of worker threads for a Detector (Limits::threads): made at
// construction, reused for every frame, joined at destruction. run() hands
// out task indices to the workers and to the calling thread (worker 0) and
// returns when all are done; it allocates nothing. With one thread nothing
// is started and run() is a plain loop on the caller.
//
// Tasks must not depend on which worker runs them for their results: each
// writes its own outputs (or per-worker scratch, indexed by `worker`), so
// the output is the same for any thread count.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace kg {

class WorkerPool {
 public:
  using Task = void (*)(void* context, int task, int worker);

  // threads >= 1, counting the caller; threads - 1 workers are started.
  explicit WorkerPool(int threads = 1);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return threads_; }

  // Runs task(context, i, worker) for i in [0, tasks), spread over the
  // threads; worker is in [0, threads()). Returns when every task ran.
  void run(int tasks, Task task, void* context);

  // The same with a callable (captured by reference; no allocation).
  template <class F>
  void run(int tasks, F& f) {
    run(
        tasks, [](void* c, int i, int w) { (*static_cast<F*>(c))(i, w); }, &f);
  }

 private:
  void work(int worker);
  void take_tasks(int worker);

  int threads_ = 1;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  std::uint64_t generation_ = 0;  // one per run(), under mutex_
  int active_ = 0;                // workers running tasks of this run, under mutex_
  bool stopping_ = false;         // under mutex_
  // The run in progress.
  Task task_ = nullptr;
  void* context_ = nullptr;
  int tasks_ = 0;
  std::atomic<int> next_{0};
};

}  // namespace kg
