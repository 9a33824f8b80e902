// The skinning worker pool: every item runs exactly once per batch, for any thread count.
#include "client/view/worker_pool.hpp"

#include <atomic>
#include <vector>

#include <gtest/gtest.h>

namespace vistel {
namespace {

class CountingJob final : public WorkerPool::Job {
 public:
  explicit CountingJob(int n) : hits(static_cast<std::size_t>(n)) {}
  void runItem(int item) override { hits[static_cast<std::size_t>(item)].fetch_add(1); }
  std::vector<std::atomic<int>> hits;
};

TEST(WorkerPool, RunsEveryItemExactlyOncePerBatch) {
  for (const int threads : {0, 1, 3}) {
    WorkerPool pool(threads);
    EXPECT_EQ(pool.threadCount(), threads);
    CountingJob job(257);
    for (int batch = 0; batch < 200; ++batch) {
      const int count = (batch * 37) % 258;  // includes empty batches
      pool.start(job, count);
      pool.wait();
      for (int i = 0; i < 257; ++i) {
        ASSERT_EQ(job.hits[static_cast<std::size_t>(i)].exchange(0), i < count ? 1 : 0)
            << "threads " << threads << " batch " << batch << " item " << i;
      }
    }
  }
}

TEST(WorkerPool, WaitWithoutABatchAndDestroyWhileIdleAreFine) {
  CountingJob job(4);  // declared first: it must outlive the pool's last batch
  WorkerPool pool(2);
  pool.wait();
  pool.start(job, 4);
  // Destroying the pool waits for the batch.
}

}  // namespace
}  // namespace vistel
