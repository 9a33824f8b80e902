// The server out of file descriptors (issue 20, finding 2): with its limit at 48 and 120
// connections knocking, the accept loop waits and retries instead of spinning, logs a
// bounded number of lines, and accepts again once descriptors are free.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/framing.hpp"
#include "control.pb.h"
#include "tests/integration/program.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

int connectTo(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

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
    const int fd = connectTo(port);
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
  const int fd = connectTo(port);
  ASSERT_GE(fd, 0);
  control::ClientMessage msg;
  control::Join& join = *msg.mutable_join();
  join.set_protocol_version(3);
  join.set_room("after");
  join.set_name("late");
  join.set_avatar_hash(std::string(64, 'a'));
  join.set_avatar_size(1000);
  const std::string payload = msg.SerializeAsString();
  std::vector<std::uint8_t> frame;
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), frame);
  ASSERT_EQ(::send(fd, frame.data(), frame.size(), 0), static_cast<ssize_t>(frame.size()));
  timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<std::uint8_t> got(4096);
  const ssize_t n = ::recv(fd, got.data(), got.size(), 0);
  ::close(fd);
  ASSERT_GT(n, 4);
  wire::FrameDecoder decoder(1u << 20);
  ASSERT_TRUE(decoder.push(std::span(got.data(), static_cast<std::size_t>(n))));
  auto reply = decoder.next();
  ASSERT_TRUE(reply.has_value());
  control::ServerMessage answer;
  ASSERT_TRUE(answer.ParseFromArray(reply->data(), static_cast<int>(reply->size())));
  EXPECT_TRUE(answer.has_welcome());
  server.signal(SIGINT);
  EXPECT_EQ(server.wait(10.0), 0);
}

}  // namespace
}  // namespace vistel
