// A fixed set of worker threads for a Detector (Limits::threads): made at
// construction, reused for every frame, joined at destruction. run() hands
// out task indices to the workers and to the calling thread (worker 0) and
// returns when all are done; it allocates nothing. With one thread nothing
// is started and run() is a plain loop on the caller.
//
// Tasks must not depend on which worker runs them for their results: each
// writes its own outputs (or per-worker scratch, indexed by `worker`), so
// the output is the same for any thread count.
//
// Nested runs: in a run started with run_with_help(), the threads that find
// no task left stay until every task is done and take part in the runs that
// the tasks still running start (one at a time; a task that starts a run
// while another task's nested run is open runs it alone). A long task, e.g.
// the one model of a frame with an appearance to align, then gets the idle
// threads' help. A nested task's `worker` is its thread's index. (A run of
// one task runs on the caller: the runs it starts are not nested.)
//
// A worker that finished a run polls for the next one for a few tens of
// microseconds before it sleeps, and the caller polls for the workers
// still in the run before it sleeps: a frame's runs (the keypoints' levels)
// follow each other closely, and waking a sleeping thread costs about as
// long as a small run.
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
  // Called from a task of this pool: a nested run (above).
  void run(int tasks, Task task, void* context) { run(tasks, task, context, false); }
  // The same, and the threads out of tasks help the nested runs (above).
  void run_with_help(int tasks, Task task, void* context) { run(tasks, task, context, true); }

  // The same with a callable (captured by reference; no allocation).
  template <class F>
  void run(int tasks, F& f) {
    run(tasks, &call<F>, &f, false);
  }
  template <class F>
  void run_with_help(int tasks, F& f) {
    run(tasks, &call<F>, &f, true);
  }

 private:
  template <class F>
  static void call(void* c, int i, int w) {
    (*static_cast<F*>(c))(i, w);
  }
  void run(int tasks, Task task, void* context, bool help);
  void run_nested(int tasks, Task task, void* context);
  void work(int worker);
  void take_tasks(int worker);
  // Takes part in nested runs until every task of the run is done.
  void help(int worker);
  bool nested_open() const;  // under mutex_

  int threads_ = 1;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_;
  std::condition_variable done_;
  std::condition_variable help_;  // a nested run opened, or the run's tasks all done
  // Changed under mutex_; read without it only to spin (worker_pool.cpp).
  std::atomic<std::uint64_t> generation_{0};  // one per run()
  std::atomic<int> active_{0};                // workers running tasks of this run
  bool stopping_ = false;                     // under mutex_
  // The run in progress.
  Task task_ = nullptr;
  void* context_ = nullptr;
  int tasks_ = 0;
  bool helping_ = false;
  std::atomic<int> next_{0};
  std::atomic<int> finished_{0};      // tasks of the run done
  std::atomic<bool> running_{false};  // a run is in progress: run() from a task nests
  // The nested run open (one at a time).
  std::atomic<bool> nested_busy_{false};
  Task nested_task_ = nullptr;  // under mutex_
  void* nested_context_ = nullptr;
  int nested_tasks_ = 0;
  int nested_active_ = 0;  // helpers in it, under mutex_
  std::atomic<int> nested_next_{0};
  std::condition_variable nested_done_;
};

}  // namespace kg
