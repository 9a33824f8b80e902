// Test helpers: the shared data folder (../shared/data beside the checkout, or
// $VISTEL_SHARED_DATA), skipping with a clear message when a file is absent, and a
// scratch folder per test.
#pragma once

#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace vistel::test {

// Absolute path of a file under the shared data folder (may not exist).
std::string sharedDataPath(const std::string& relative);

// The build folder (where programs such as vistel-avatar are).
std::string binaryDir();

// A fresh, empty folder for this test's outputs (under the build folder).
std::string scratchDir();

}  // namespace vistel::test

// Skips the current test, naming the missing file, when a shared-data file is absent.
#define VISTEL_REQUIRE_SHARED(path_var, relative)                                     \
  const std::string path_var = ::vistel::test::sharedDataPath(relative);              \
  if (!std::ifstream(path_var).good()) {                                              \
    GTEST_SKIP() << "shared test data not found: " << path_var                        \
                 << " (set VISTEL_SHARED_DATA or place shared/ beside the checkout)"; \
  }
