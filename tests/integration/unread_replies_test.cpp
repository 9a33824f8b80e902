// A peer that asks and never reads (issue 20, finding 1): it joins, uploads its avatar,
// then sends AvatarRequest after AvatarRequest without reading a byte. The server drops
// it once its unwritten replies pass the per-connection limit, instead of holding them
// without bound, and keeps serving everyone else.
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/raw_control.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

TEST(UnreadReplies, APeerThatNeverReadsIsDroppedAtItsLimit) {
  const std::string dir = test::scratchDir();
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
  ASSERT_LT(avatar.bytes.size(), 60000u);
  ASSERT_TRUE(writeFileText(dir + "/server.toml",
                            "[limits]\n"
                            "max_avatar_bytes = 65536\n"
                            "avatar_chunk_bytes = 8192\n"
                            "max_frame_bytes = 32768\n"
                            "max_queued_bytes_per_connection = 131072\n"
                            "max_queued_bytes_total = 262144\n"
                            "control_rate_hz = 100000.0\n"
                            "control_burst = 100000\n"));
  test::Program server("vistel-server", {"--port", "0", "--config", dir + "/server.toml"},
                       dir + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty());
  const auto port = static_cast<std::uint16_t>(std::stoi(address.substr(address.rfind(':') + 1)));

  const int greedy = test::connectLoopback(port, 4096);
  ASSERT_GE(greedy, 0);
  ASSERT_TRUE(test::sendControl(
      greedy, test::joinRequest("reads", "greedy", avatar.hash, avatar.bytes.size())));
  control::ClientMessage chunk;
  chunk.mutable_avatar_chunk()->set_hash(avatar.hash);
  chunk.mutable_avatar_chunk()->set_total_size(avatar.bytes.size());
  for (std::size_t at = 0; at < avatar.bytes.size(); at += 8192) {
    const std::size_t n = std::min<std::size_t>(8192, avatar.bytes.size() - at);
    chunk.mutable_avatar_chunk()->set_offset(at);
    chunk.mutable_avatar_chunk()->set_data(reinterpret_cast<const char*>(avatar.bytes.data() + at),
                                           n);
    ASSERT_TRUE(test::sendControl(greedy, chunk));
  }
  ASSERT_TRUE(server.waitForLog("uploaded by 'greedy'", 10.0)) << server.log();
  // Ask for our own avatar again and again; read nothing.
  control::ClientMessage request;
  request.mutable_avatar_request()->set_hash(avatar.hash);
  int sent = 0;
  for (; sent < 4000; ++sent) {
    if (!test::sendControl(greedy, request)) break;  // dropped: the server closed it
    if (server.log().find("peer is not reading") != std::string::npos) break;
  }
  EXPECT_TRUE(server.waitForLog("peer is not reading", 10.0)) << "after " << sent << " requests";
  EXPECT_NE(server.log().find("per-connection limit"), std::string::npos) << server.log();
  ::close(greedy);

  // Everyone else is still served: a newcomer joins and gets its Welcome.
  const int polite = test::connectLoopback(port, 0);
  ASSERT_GE(polite, 0);
  ASSERT_TRUE(test::sendControl(
      polite, test::joinRequest("reads", "polite", avatar.hash, avatar.bytes.size())));
  const auto answer = test::receiveControl(polite, 5);
  ::close(polite);
  ASSERT_TRUE(answer.has_value());
  EXPECT_TRUE(answer->has_welcome()) << answer->ShortDebugString() << "\n" << server.log();
  server.signal(SIGINT);
  EXPECT_EQ(server.wait(10.0), 0);
}

}  // namespace
}  // namespace vistel
