// A fixed pool of worker threads for splitting per-frame kernels over index ranges
// (Step 2 over vertex chunks). Results must not depend on which thread runs a task: the
// kernels write disjoint ranges and reduce in task order, so 1 and N threads give the
// same bits. run() allocates nothing; the threads live as long as the pool.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace vistel {

class TaskPool {
 public:
  // threads >= 1 (the calling thread counts as one; threads - 1 workers are started).
  explicit TaskPool(int threads);
  ~TaskPool();
  TaskPool(const TaskPool&) = delete;
  TaskPool& operator=(const TaskPool&) = delete;

  int threadCount() const { return static_cast<int>(workers_.size()) + 1; }

  // Calls fn(ctx, t) for t in [0, count) across the threads; returns when all are done.
  // Not re-entrant (one run at a time per pool).
  void run(int count, void (*fn)(void*, int), void* ctx);

 private:
  void workerLoop();
  void drain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
  int count_ = 0;
  void (*fn_)(void*, int) = nullptr;
  void* ctx_ = nullptr;
  std::atomic<int> next_{0};
  std::atomic<int> finished_{0};
  int busy_workers_ = 0;
};

// Runs f(t) for t in [0, count) on the pool, or inline when pool is null.
template <typename F>
void parallelFor(TaskPool* pool, int count, F& f) {
  if (pool == nullptr || pool->threadCount() == 1 || count <= 1) {
    for (int t = 0; t < count; ++t) f(t);
    return;
  }
  pool->run(
      count, [](void* ctx, int t) { (*static_cast<F*>(ctx))(t); }, &f);
}

}  // namespace vistel
