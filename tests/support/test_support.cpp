#include "tests/support/test_support.hpp"

#include <cstdlib>
#include <filesystem>

namespace vistel::test {

std::string sharedDataPath(const std::string& relative) {
  const char* env = std::getenv("VISTEL_SHARED_DATA");
  const std::string root = env != nullptr && *env != '\0' ? env : VISTEL_DEFAULT_SHARED_DATA;
  return (std::filesystem::path(root) / relative).lexically_normal().string();
}

std::string binaryDir() { return VISTEL_BINARY_DIR; }

std::string scratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(VISTEL_BINARY_DIR) / "test-scratch";
  if (info != nullptr) dir /= std::string(info->test_suite_name()) + "." + info->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace vistel::test
