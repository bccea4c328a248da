#include "core/support/worker_pool.h"

#include <chrono>

namespace kg {

namespace {

// The index of the pool thread this is (0: the caller's), for nested runs.
thread_local int this_worker = 0;

// How long a thread polls before it sleeps on a condition variable.
constexpr std::chrono::microseconds kSpin{50};

void pause_briefly() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__) || (defined(__arm__) && defined(__ARM_ARCH) && __ARM_ARCH >= 7)
  asm volatile("yield");
#endif
}

// Polls `done` for up to kSpin; true when it held.
template <class Done>
bool spin_until(Done done) {
  const auto until = std::chrono::steady_clock::now() + kSpin;
  for (unsigned n = 1;; ++n) {
    if (done()) return true;
    pause_briefly();
    if ((n & 63) == 0 && std::chrono::steady_clock::now() > until) return false;
  }
}

}  // namespace

WorkerPool::WorkerPool(int threads) : threads_(threads < 1 ? 1 : threads) {
  workers_.reserve(static_cast<std::size_t>(threads_ - 1));
  for (int w = 1; w < threads_; ++w) workers_.emplace_back([this, w] { work(w); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::take_tasks(int worker) {
  for (int i = next_.fetch_add(1, std::memory_order_relaxed); i < tasks_;
       i = next_.fetch_add(1, std::memory_order_relaxed)) {
    task_(context_, i, worker);
    if (finished_.fetch_add(1, std::memory_order_acq_rel) + 1 == tasks_ && helping_) {
      // Under the lock: a helper between its test and its wait cannot miss it.
      std::lock_guard<std::mutex> lock(mutex_);
      help_.notify_all();
    }
  }
  if (helping_) help(worker);
}

bool WorkerPool::nested_open() const {
  return nested_task_ != nullptr && nested_next_.load(std::memory_order_relaxed) < nested_tasks_;
}

void WorkerPool::help(int worker) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    help_.wait(lock, [this] {
      return finished_.load(std::memory_order_acquire) >= tasks_ || nested_open();
    });
    if (finished_.load(std::memory_order_acquire) >= tasks_) return;
    // Joining under the lock: the nested run cannot close while this
    // thread is in it (run_nested waits for nested_active_ == 0).
    ++nested_active_;
    const Task task = nested_task_;
    void* const context = nested_context_;
    const int tasks = nested_tasks_;
    lock.unlock();
    for (int i = nested_next_.fetch_add(1, std::memory_order_relaxed); i < tasks;
         i = nested_next_.fetch_add(1, std::memory_order_relaxed))
      task(context, i, worker);
    lock.lock();
    if (--nested_active_ == 0) nested_done_.notify_all();
  }
}

void WorkerPool::run_nested(int tasks, Task task, void* context) {
  const int self = this_worker;
  bool idle = false;
  if (!helping_ || !nested_busy_.compare_exchange_strong(idle, true, std::memory_order_acquire)) {
    for (int i = 0; i < tasks; ++i) task(context, i, self);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    nested_task_ = task;
    nested_context_ = context;
    nested_tasks_ = tasks;
    nested_next_.store(0, std::memory_order_relaxed);
    help_.notify_all();
  }
  for (int i = nested_next_.fetch_add(1, std::memory_order_relaxed); i < tasks;
       i = nested_next_.fetch_add(1, std::memory_order_relaxed))
    task(context, i, self);
  {
    std::unique_lock<std::mutex> lock(mutex_);
    nested_done_.wait(lock, [this] { return nested_active_ == 0; });
    nested_task_ = nullptr;
  }
  nested_busy_.store(false, std::memory_order_release);
}

void WorkerPool::run(int tasks, Task task, void* context, bool help) {
  if (tasks <= 0) return;
  if (workers_.empty() || tasks == 1) {
    for (int i = 0; i < tasks; ++i) task(context, i, this_worker);
    return;
  }
  if (running_.load(std::memory_order_acquire)) {
    run_nested(tasks, task, context);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = task;
    context_ = context;
    tasks_ = tasks;
    helping_ = help;
    next_.store(0, std::memory_order_relaxed);
    finished_.store(0, std::memory_order_relaxed);
    running_.store(true, std::memory_order_release);
    generation_.fetch_add(1, std::memory_order_release);
  }
  start_.notify_all();
  take_tasks(0);
  // Every task is claimed now (and, helping, done); wait only for the
  // workers still running one. A worker that wakes later finds nothing left
  // and does not join this run (work()), so a busy machine's slow wake-ups
  // do not hold the frame up.
  spin_until([this] { return active_.load(std::memory_order_acquire) == 0; });
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return active_.load(std::memory_order_relaxed) == 0; });
  running_.store(false, std::memory_order_release);
}

void WorkerPool::work(int worker) {
  this_worker = worker;
  std::uint64_t seen = 0;
  for (;;) {
    // The next run usually starts within microseconds (above).
    spin_until([&] { return generation_.load(std::memory_order_acquire) != seen; });
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock,
                  [&] { return stopping_ || generation_.load(std::memory_order_relaxed) != seen; });
      if (stopping_) return;
      seen = generation_.load(std::memory_order_relaxed);
      // Joining under the lock: run() cannot return (nor the next run
      // change task_, context_ and tasks_) while this worker is active. A
      // helping run is joined while a task is still running.
      const bool claimable = next_.load(std::memory_order_relaxed) < tasks_;
      const bool unfinished = helping_ && finished_.load(std::memory_order_acquire) < tasks_;
      if (!claimable && !unfinished) continue;
      ++active_;
    }
    take_tasks(worker);
    std::lock_guard<std::mutex> lock(mutex_);
    if (active_.fetch_sub(1, std::memory_order_release) == 1) done_.notify_one();
  }
}

}  // namespace kg
