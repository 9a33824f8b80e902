// A pause of the server (SIGSTOP, a starved thread) is not its members' silence: after
// it, nobody is dropped for the time the server itself did not run, and the datagrams
// that queued meanwhile still count. Members silent after the pause time out as before.
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/wire/packets.hpp"
#include "server/core/lobby.hpp"
#include "server/core/room.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/control_frames.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using test::seatedEndpoint;

std::vector<std::uint8_t> pingFrom(int i) {
  wire::PingPacket ping;
  ping.header = {test::seatedMemberId(i), 0};
  ping.ping_id = 1;
  ping.client_time = 1.0;
  std::vector<std::uint8_t> out;
  wire::write(ping, out);
  return test::sealAs(ping.header.member_id, std::move(out));
}

TEST(ServerPause, MembersAreNotDroppedForAPauseOfTheServer) {
  spdlog::set_level(spdlog::level::err);
  RoomSettings settings;
  settings.member_timeout_s = 10.0;
  Room room(RoomId{1}, "pause", settings, 0.0);
  for (int i = 0; i < 2; ++i) {
    RoomCommand c;
    c.kind = RoomCommand::Kind::kAddMember;
    c.room = RoomId{1};
    c.member = MemberId{test::seatedMemberId(i)};
    test::setTestKeys(c);
    c.joint_count = 5;
    room.apply(c, 0.0);
    c.kind = RoomCommand::Kind::kBindEndpoint;
    c.endpoint = seatedEndpoint(i);
    room.apply(c, 0.0);
  }
  Effects fx;
  for (double t = 0.0; t < 1.0; t += 0.05) {
    for (int i = 0; i < 2; ++i) room.onDatagram(pingFrom(i), seatedEndpoint(i), t, fx);
    room.update(t, fx);
  }
  // The server stops for 12 s (longer than the 10 s timeout), then runs its timers before
  // it reads what queued.
  room.update(13.0, fx);
  EXPECT_TRUE(fx.timed_out.empty());
  room.onDatagram(pingFrom(0), seatedEndpoint(0), 13.001, fx);
  // Member 0 keeps talking; member 1 stays silent and times out 10 s after the pause.
  for (double t = 13.05; t < 22.9; t += 0.05) {
    room.onDatagram(pingFrom(0), seatedEndpoint(0), t, fx);
    room.update(t, fx);
  }
  EXPECT_TRUE(fx.timed_out.empty());
  for (double t = 22.9; t < 23.5; t += 0.05) {
    room.onDatagram(pingFrom(0), seatedEndpoint(0), t, fx);
    room.update(t, fx);
  }
  ASSERT_EQ(fx.timed_out.size(), 1u);
  EXPECT_EQ(fx.timed_out[0].value, 0x00010001u);
}

TEST(ServerPause, AnUploadIsNotStalledByAPauseOfTheServer) {
  spdlog::set_level(spdlog::level::err);
  ServerConfig config;
  config.upload_stall_timeout_s = 15.0;
  config.upload_min_rate_bytes_per_s = 0.0;  // the stall timeout alone (no rate floor)
  config.upload_deadline_base_s = 3600.0;
  Lobby lobby(config, 5);
  Effects fx;
  lobby.onConnect(7, 0.0, fx);
  lobby.onStreamBytes(
      7, test::frameOf(test::joinMessage("r", "up", std::string(64, 'c'), 5000, kProtocolVersion)),
      0.0, fx);
  ASSERT_EQ(lobby.memberCount(), 1);
  ASSERT_EQ(lobby.uploadBytesInFlight(), 5000u);
  for (double t = 0.25; t < 1.0; t += 0.25) lobby.update(t, fx);
  fx = {};
  lobby.update(20.0, fx);  // 19 s of pause
  EXPECT_TRUE(fx.closes.empty());
  EXPECT_EQ(lobby.memberCount(), 1);
  // No chunk after the pause either: stalled 15 s of running time after the join (the
  // last update before the pause was at 0.75 s, so the pause counts 19.25 s).
  for (double t = 20.25; t < 34.1; t += 0.25) lobby.update(t, fx);
  EXPECT_TRUE(fx.closes.empty());
  for (double t = 34.25; t < 35.0; t += 0.25) lobby.update(t, fx);
  EXPECT_EQ(fx.closes.size(), 1u);
  EXPECT_EQ(lobby.memberCount(), 0);
}

}  // namespace
}  // namespace vistel::server
