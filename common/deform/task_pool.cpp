#include "common/deform/task_pool.hpp"

namespace vistel {

TaskPool::TaskPool(int threads) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { workerLoop(); });
}

TaskPool::~TaskPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void TaskPool::drain() {
  // Claim tasks until none are left.
  for (int t = next_.fetch_add(1); t < count_; t = next_.fetch_add(1)) {
    fn_(ctx_, t);
    finished_.fetch_add(1);
  }
}

void TaskPool::run(int count, void (*fn)(void*, int), void* ctx) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    count_ = count;
    fn_ = fn;
    ctx_ = ctx;
    next_.store(0);
    finished_.store(0);
    busy_workers_ = static_cast<int>(workers_.size());
    ++generation_;
  }
  wake_.notify_all();
  drain();
  // Wait until every task finished and every worker has left this generation.
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return busy_workers_ == 0; });
}

void TaskPool::workerLoop() {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    drain();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --busy_workers_;
    }
    done_.notify_all();
  }
}

}  // namespace vistel
