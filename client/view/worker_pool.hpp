// A small fixed pool of worker threads that runs one batch of numbered items at a time
// (the skinning of every member's vertex chunks). The thread that calls wait() helps.
// Which thread runs which item is unspecified, so items must write disjoint outputs;
// results then do not depend on the number of threads.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace vistel {

class WorkerPool {
 public:
  // What a batch runs: item i in [0, count), each exactly once, on any thread.
  class Job {
   public:
    virtual void runItem(int item) = 0;

   protected:
    ~Job() = default;
  };

  // threads >= 0 workers (0: wait() runs everything on the calling thread).
  explicit WorkerPool(int threads);
  ~WorkerPool();  // joins the workers (after waiting for a running batch)
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Starts a batch and returns at once; `job` must outlive it. The previous batch must
  // have been waited for. Allocates nothing.
  void start(Job& job, int count);
  // Runs remaining items on the calling thread, then blocks until the batch is done
  // and no worker still touches it. No-op when no batch is running.
  void wait();

  int threadCount() const { return static_cast<int>(threads_.size()); }

 private:
  void workerLoop();
  void drain(Job& job, int count);

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_cv_;
  std::condition_variable done_cv_;
  std::uint64_t generation_ = 0;  // batches started (guarded by mutex_)
  Job* job_ = nullptr;            // current batch (guarded by mutex_)
  int count_ = 0;
  int active_ = 0;  // workers inside drain() of the current batch
  bool stop_ = false;
  bool running_ = false;           // a batch was started and not yet waited for
  std::atomic<int> next_{0};       // next item to claim
  std::atomic<int> remaining_{0};  // items not yet finished
};

}  // namespace vistel
