// Counts heap allocations made through operator new while a scope is active (this test
// binary replaces the global operator new), for "allocates nothing per frame" checks.
#pragma once

namespace vistel::test {

class AllocationCounter {
 public:
  AllocationCounter();
  ~AllocationCounter();
  long count() const;
};

}  // namespace vistel::test
