#include "client/view/worker_pool.hpp"

#include <cassert>

namespace vistel {

WorkerPool::WorkerPool(int threads) {
  threads_.reserve(static_cast<std::size_t>(std::max(threads, 0)));
  for (int i = 0; i < threads; ++i) threads_.emplace_back([this] { workerLoop(); });
}

WorkerPool::~WorkerPool() {
  wait();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void WorkerPool::start(Job& job, int count) {
  assert(!running_ && "wait() for the previous batch first");
  {
    // A worker that woke late for the previous batch may still be leaving drain(); let it
    // go before the counters are reset, or it could claim a new item for the old job.
    std::unique_lock lock(mutex_);
    done_cv_.wait(lock, [&] { return active_ == 0; });
    job_ = &job;
    count_ = count;
    next_.store(0, std::memory_order_relaxed);
    remaining_.store(count, std::memory_order_relaxed);
    ++generation_;
    running_ = true;
  }
  if (count > 0) start_cv_.notify_all();
}

void WorkerPool::drain(Job& job, int count) {
  // Claim items until none are left; the last finisher wakes the waiter.
  for (int i = next_.fetch_add(1, std::memory_order_relaxed); i < count;
       i = next_.fetch_add(1, std::memory_order_relaxed)) {
    job.runItem(i);
    if (remaining_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
      std::lock_guard lock(mutex_);
      done_cv_.notify_all();
    }
  }
}

void WorkerPool::workerLoop() {
  std::uint64_t seen = 0;
  for (;;) {
    Job* job = nullptr;
    int count = 0;
    {
      std::unique_lock lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      job = job_;
      count = count_;
      ++active_;
    }
    drain(*job, count);
    {
      std::lock_guard lock(mutex_);
      --active_;
    }
    done_cv_.notify_all();
  }
}

void WorkerPool::wait() {
  if (!running_) return;
  Job* job = nullptr;
  int count = 0;
  {
    std::lock_guard lock(mutex_);
    job = job_;
    count = count_;
  }
  drain(*job, count);
  // Done when every item finished and no worker is still inside this batch's drain()
  // (so a worker cannot claim an item of the next batch with this batch's job).
  std::unique_lock lock(mutex_);
  done_cv_.wait(lock,
                [&] { return remaining_.load(std::memory_order_acquire) == 0 && active_ == 0; });
  running_ = false;
}

}  // namespace vistel
