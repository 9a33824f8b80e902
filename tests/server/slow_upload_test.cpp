// Slow uploads and per-address rooms (issue 20, finding 5): four members announcing 16 MiB
// avatars and trickling a byte every 10 s used to hold the whole upload budget, so every
// newcomer with a new avatar was refused with SERVER_FULL for as long as they kept it up.
// Now an upload under the rate floor is aborted after its grace, and the newcomer gets the
// slot. One address cannot open more rooms than max_rooms_per_address.
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "server/core/lobby.hpp"
#include "server/core/server_core.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/server/control_frames.hpp"

namespace vistel::server {
namespace {

using test::SimNetwork;

constexpr std::uint64_t kBig = 16u << 20;  // the largest avatar the server accepts

std::string hashOf(char c) { return std::string(64, c); }

control::ClientMessage chunkOf(const std::string& hash, std::uint64_t total, std::uint64_t offset,
                               std::size_t size) {
  control::ClientMessage msg;
  msg.mutable_avatar_chunk()->set_hash(hash);
  msg.mutable_avatar_chunk()->set_total_size(total);
  msg.mutable_avatar_chunk()->set_offset(offset);
  msg.mutable_avatar_chunk()->set_data(std::string(size, 'x'));
  return msg;
}

TEST(SlowUpload, TricklingUploadsAreAbortedAndANewcomerGetsTheSlot) {
  spdlog::set_level(spdlog::level::off);
  ServerConfig config;  // the defaults: 64 MiB of uploads, a 64 KiB/s floor after 5 s
  config.control_burst = 1000;
  SimNetwork net(config, 77);
  // Four slow peers reserve the whole upload budget.
  const std::vector<ConnId> slow = {901, 902, 903, 904};
  for (std::size_t k = 0; k < slow.size(); ++k) {
    net.injectConnect(slow[k]);
    net.injectStream(
        slow[k], test::frameOf(test::joinMessage("lab", fmt::format("slow{}", k),
                                                 hashOf(char('a' + k)), kBig, kProtocolVersion)));
  }
  ASSERT_EQ(net.server().lobby().uploadBytesInFlight(), 4 * kBig);
  // They trickle a byte every 10 s: never stalled by the 15 s timeout.
  std::uint64_t sent = 0;
  for (int round = 0; round < 3; ++round) {
    net.advance(10.0, 0.05);
    for (std::size_t k = 0; k < slow.size(); ++k) {
      if (net.rawClosed(slow[k])) continue;
      net.injectStream(slow[k], test::frameOf(chunkOf(hashOf(char('a' + k)), kBig, sent, 1)));
    }
    ++sent;
  }
  // Each was aborted with a clear reply, and its reservation freed.
  for (ConnId conn : slow) {
    EXPECT_TRUE(net.rawClosed(conn)) << conn;
    const auto replies = test::messagesOf(net.rawReceived(conn));
    ASSERT_FALSE(replies.empty()) << conn;
    ASSERT_TRUE(replies.back().has_error()) << conn;
    EXPECT_EQ(replies.back().error().code(), control::ErrorReply::TIMEOUT);
    EXPECT_NE(replies.back().error().message().find("too slow"), std::string::npos)
        << replies.back().error().message();
  }
  EXPECT_EQ(net.server().lobby().drops().count("upload too slow"), slow.size());
  EXPECT_EQ(net.server().lobby().uploadBytesInFlight(), 0u);

  // A newcomer with a new 16 MiB avatar is asked to upload it, not refused.
  constexpr ConnId kNewcomer = 950;
  net.injectConnect(kNewcomer);
  net.injectStream(kNewcomer, test::frameOf(test::joinMessage("lab", "new", hashOf('f'), kBig,
                                                              kProtocolVersion)));
  const auto replies = test::messagesOf(net.rawReceived(kNewcomer));
  ASSERT_FALSE(replies.empty());
  ASSERT_TRUE(replies.front().has_welcome())
      << (replies.front().has_error() ? replies.front().error().message() : "");
  EXPECT_TRUE(replies.front().welcome().upload_avatar());
}

TEST(SlowUpload, AnUploadAtTheFloorGoesOnAndOnePastItsDeadlineIsAborted) {
  spdlog::set_level(spdlog::level::off);
  ServerConfig config;
  config.upload_min_rate_bytes_per_s = 1000.0;
  config.upload_deadline_base_s = 10.0;
  config.upload_deadline_rate_bytes_per_s = 2000.0;  // 100 kB: 10 + 50 s
  config.control_burst = 1000;
  Lobby lobby(config, 3);
  Effects fx;
  lobby.onConnect(1, 0.0, fx);
  const std::string hash = hashOf('d');
  constexpr std::uint64_t kSize = 100000;
  lobby.onStreamBytes(
      1, test::frameOf(test::joinMessage("r", "steady", hash, kSize, kProtocolVersion)), 0.0, fx);
  ASSERT_EQ(lobby.uploadBytesInFlight(), kSize);
  // 1.1 kB every second: above the floor, so it goes on, but 100 kB would take 91 s.
  std::uint64_t offset = 0;
  double t = 0.0;
  for (int s = 1; s <= 59; ++s) {
    for (int q = 0; q < 4; ++q) {
      t += 0.25;
      lobby.update(t, fx);
    }
    lobby.onStreamBytes(1, test::frameOf(chunkOf(hash, kSize, offset, 1100)), t, fx);
    offset += 1100;
    ASSERT_TRUE(fx.closes.empty()) << "closed at " << t;
  }
  // The deadline (60 s) passes before the file is done.
  for (int q = 0; q < 8; ++q) {
    t += 0.25;
    lobby.update(t, fx);
  }
  ASSERT_EQ(fx.closes.size(), 1u);
  EXPECT_EQ(lobby.drops().count("upload deadline"), 1u);
  EXPECT_EQ(lobby.uploadBytesInFlight(), 0u);
}

TEST(RoomsPerAddress, OneAddressOpensAtMostTheLimit) {
  spdlog::set_level(spdlog::level::off);
  ServerConfig config;
  config.max_rooms_per_address = 2;
  Lobby lobby(config, 9);
  Effects fx;
  const std::string stored_hash = hashOf('e');
  const auto join = [&](ConnId conn, const std::string& address, const std::string& room) {
    lobby.onConnect(conn, 0.0, fx);
    lobby.setConnectionAddress(conn, address);
    lobby.onStreamBytes(conn,
                        test::frameOf(test::joinMessage(room, fmt::format("m{}", conn), stored_hash,
                                                        2000, kProtocolVersion)),
                        0.0, fx);
  };
  join(1, "127.0.0.2", "one");
  join(2, "127.0.0.2", "two");
  EXPECT_EQ(lobby.roomCount(), 2);
  // A third room from the same address is refused; joining an open room is not.
  join(3, "127.0.0.2", "three");
  EXPECT_EQ(lobby.roomCount(), 2);
  EXPECT_EQ(lobby.drops().count("rooms per address"), 1u);
  join(4, "127.0.0.2", "one");
  EXPECT_EQ(lobby.memberCount(), 3);
  // Another address may; an unlimited (unset) one too.
  join(5, "127.0.0.3", "four");
  join(6, "", "five");
  EXPECT_EQ(lobby.roomCount(), 4);
  // A room that closes gives its creator's count back.
  lobby.onDisconnect(2, 1.0, fx);
  EXPECT_EQ(lobby.roomCount(), 3);
  join(7, "127.0.0.2", "six");
  EXPECT_EQ(lobby.roomCount(), 4);
  EXPECT_EQ(lobby.drops().count("rooms per address"), 1u);
}

}  // namespace
}  // namespace vistel::server
