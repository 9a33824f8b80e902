// Test-only: counts every global operator new of the test binary (allocation_counter.cpp
// replaces it), so a test can check that a per-frame call allocates nothing.
#pragma once

namespace vistel::test {

// Number of operator new calls so far in this process.
long allocationCount();

}  // namespace vistel::test
