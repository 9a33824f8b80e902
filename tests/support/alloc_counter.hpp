// Test-only allocation counting. A test binary that links vistel_alloc_counter has its
// global operator new replaced by a counting, malloc-backed one, so a test can check that
// a per-frame call allocates nothing (STYLE.md: no heap allocation per frame).
#pragma once

namespace vistel::test {

// Calls of operator new (every form) made by any thread since the process started.
long allocationCount();

// Counts the operator new calls made by any thread while it lives.
class AllocationCounter {
 public:
  AllocationCounter() : start_(allocationCount()) {}
  long count() const { return allocationCount() - start_; }

 private:
  long start_;
};

}  // namespace vistel::test
