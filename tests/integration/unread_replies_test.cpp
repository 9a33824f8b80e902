// A peer that asks and never reads (issue 20, finding 1): it joins, uploads its avatar,
// then sends AvatarRequest after AvatarRequest without reading a byte. The server drops
// it once its unwritten replies pass the per-connection limit, instead of holding them
// without bound, and keeps serving everyone else.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "common/wire/framing.hpp"
#include "control.pb.h"
#include "tests/integration/program.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

int connectTo(std::uint16_t port, int receive_buffer) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  if (receive_buffer > 0) {
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  }
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

bool sendMessage(int fd, const control::ClientMessage& msg) {
  const std::string payload = msg.SerializeAsString();
  std::vector<std::uint8_t> frame;
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), frame);
  return ::send(fd, frame.data(), frame.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(frame.size());
}

control::ClientMessage joinOf(const std::string& name, const test::EncodedAvatar& avatar) {
  control::ClientMessage msg;
  control::Join& join = *msg.mutable_join();
  join.set_protocol_version(3);
  join.set_room("reads");
  join.set_name(name);
  join.set_avatar_hash(avatar.hash);
  join.set_avatar_size(avatar.bytes.size());
  return msg;
}

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

  const int greedy = connectTo(port, 4096);
  ASSERT_GE(greedy, 0);
  ASSERT_TRUE(sendMessage(greedy, joinOf("greedy", avatar)));
  control::ClientMessage chunk;
  chunk.mutable_avatar_chunk()->set_hash(avatar.hash);
  chunk.mutable_avatar_chunk()->set_total_size(avatar.bytes.size());
  for (std::size_t at = 0; at < avatar.bytes.size(); at += 8192) {
    const std::size_t n = std::min<std::size_t>(8192, avatar.bytes.size() - at);
    chunk.mutable_avatar_chunk()->set_offset(at);
    chunk.mutable_avatar_chunk()->set_data(reinterpret_cast<const char*>(avatar.bytes.data() + at),
                                           n);
    ASSERT_TRUE(sendMessage(greedy, chunk));
  }
  ASSERT_TRUE(server.waitForLog("uploaded by 'greedy'", 10.0)) << server.log();
  // Ask for our own avatar again and again; read nothing.
  control::ClientMessage request;
  request.mutable_avatar_request()->set_hash(avatar.hash);
  int sent = 0;
  for (; sent < 4000; ++sent) {
    if (!sendMessage(greedy, request)) break;  // dropped: the server closed it
    if (server.log().find("peer is not reading") != std::string::npos) break;
  }
  EXPECT_TRUE(server.waitForLog("peer is not reading", 10.0)) << "after " << sent << " requests";
  EXPECT_NE(server.log().find("per-connection limit"), std::string::npos) << server.log();
  ::close(greedy);

  // Everyone else is still served: a newcomer joins and gets its Welcome.
  const int polite = connectTo(port, 0);
  ASSERT_GE(polite, 0);
  ASSERT_TRUE(sendMessage(polite, joinOf("polite", avatar)));
  timeval timeout{5, 0};
  ::setsockopt(polite, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<std::uint8_t> got(1 << 16);
  const ssize_t n = ::recv(polite, got.data(), got.size(), 0);
  ::close(polite);
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
