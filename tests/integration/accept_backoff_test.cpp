// The server out of file descriptors (issue 20, finding 2): with its limit at 48 and 120
// connections knocking, the accept loop waits and retries instead of spinning, logs a
// bounded number of lines, and accepts again once descriptors are free.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/integration/program.hpp"
#include "tests/integration/raw_control.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

int countOf(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(AcceptBackoff, OutOfDescriptorsTheServerWaitsLogsLittleAndRecovers) {
  const std::string dir = test::scratchDir();
  // The server inherits a soft limit of 48 descriptors; ours comes back right after.
  rlimit original{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &original), 0);
  rlimit low = original;
  low.rlim_cur = 48;
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
  test::Program server("vistel-server", {"--port", "0"}, dir + "/server.log", true);
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &original), 0);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty());
  const auto port = static_cast<std::uint16_t>(std::stoi(address.substr(address.rfind(':') + 1)));

  // 120 connections: the kernel completes them (backlog), the server runs out of
  // descriptors accepting them.
  std::vector<int> fds;
  for (int i = 0; i < 120; ++i) {
    const int fd = test::connectLoopback(port);
    if (fd >= 0) fds.push_back(fd);
  }
  EXPECT_GT(fds.size(), 60u);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::string log = server.log();
  const int reports = countOf(log, "accept failed");
  std::printf("[ measure  ] %zu connections, %d accept-failure lines in 1.5 s\n", fds.size(),
              reports);
  EXPECT_GE(reports, 1);
  EXPECT_LE(reports, 2);
  for (int fd : fds) ::close(fd);

  // Descriptors free again: a join is answered.
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  const int fd = test::connectLoopback(port);
  ASSERT_GE(fd, 0);
  ASSERT_TRUE(
      test::sendControl(fd, test::joinRequest("after", "late", std::string(64, 'a'), 1000)));
  const auto answer = test::receiveControl(fd, 5);
  ::close(fd);
  ASSERT_TRUE(answer.has_value());
  EXPECT_TRUE(answer->has_welcome());
  server.signal(SIGINT);
  EXPECT_EQ(server.wait(10.0), 0);
}

}  // namespace
}  // namespace vistel
