// Selective forwarding of voice (server/core/voice_forwarding.hpp, Room::onVoice): a frame
// reaches the members within the hearing radius, unchanged; a listener gets at most
// max_speakers speakers, the loudest at its ear, without cutting anyone off mid-word; each
// speaker is rate-limited; malformed and forged frames are dropped with a reason.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/scene/seat_layout.hpp"
#include "common/wire/voice_packets.hpp"
#include "server/core/room.hpp"
#include "server/core/server_config.hpp"
#include "server/core/voice_forwarding.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using test::seatedEndpoint;
using test::seatedMemberId;

const std::vector<std::uint8_t> kOpus = {0xF8, 0x01, 0x02, 0x03};

std::vector<std::uint8_t> voiceFrom(int i, std::uint16_t sequence, std::uint8_t level = 20) {
  wire::VoicePacket p;
  p.header.member_id = seatedMemberId(i);
  p.frame.sequence = sequence;
  p.frame.capture_time = 960u * sequence;
  p.frame.level = level;
  p.payload = kOpus;
  std::vector<std::uint8_t> out;
  EXPECT_TRUE(wire::writeVoice(p, out));
  return test::sealAs(seatedMemberId(i), out);
}

// Recipient index -> speaker ids of the VoiceForward datagrams in fx (each checked).
std::map<int, std::vector<std::uint32_t>> forwards(const Effects& fx) {
  std::map<int, std::vector<std::uint32_t>> out;
  for (const OutDatagram& d : fx.datagrams) {
    const int to = d.to.port - test::kSeatedPortBase;
    const std::vector<std::uint8_t> plain = test::openFor(seatedMemberId(to), d.bytes);
    wire::VoiceForwardPacket f;
    EXPECT_TRUE(wire::readVoiceForward(plain, f)) << "to " << to;
    EXPECT_EQ(std::vector<std::uint8_t>(f.payload.begin(), f.payload.end()), kOpus);
    out[to].push_back(f.speaker_id);
  }
  return out;
}

TEST(VoiceForwarding, AFrameReachesTheOthersUnchangedSealedForEach) {
  spdlog::set_level(spdlog::level::err);
  Room room(RoomId{1}, "voice", RoomSettings{}, 0.0);
  test::seatMembers(room, 4);
  Effects fx;
  room.onDatagram(voiceFrom(0, 7), seatedEndpoint(0), 0.01, fx);
  const auto got = forwards(fx);
  EXPECT_EQ(got.size(), 3u);
  EXPECT_EQ(got.count(0), 0u);  // never back to the speaker
  for (int to = 1; to < 4; ++to)
    EXPECT_EQ(got.at(to), std::vector<std::uint32_t>{seatedMemberId(0)});
  EXPECT_EQ(room.voiceStats().frames, 1u);
  EXPECT_EQ(room.voiceStats().forwarded, 3u);
  // Sequence, capture time and level as sent.
  wire::VoiceForwardPacket f;
  const auto plain = test::openFor(seatedMemberId(1), fx.datagrams[0].bytes);
  ASSERT_TRUE(wire::readVoiceForward(plain, f));
  EXPECT_EQ(f.frame.sequence, 7);
  EXPECT_EQ(f.frame.capture_time, 960u * 7);
  EXPECT_EQ(f.frame.level, 20);
}

TEST(VoiceForwarding, OnlyListenersWithinTheHearingRadius) {
  spdlog::set_level(spdlog::level::err);
  // The default seats: 1.5 m (seat 3), 2.6 m (seat 2) and 3 m (seat 1) from seat 0. Heads
  // are 1.6 m above the seats until the server has the avatars.
  auto distance = [](int a, int b) {
    const SeatPlacement pa = seatPlacement(a, SeatLayout{}), pb = seatPlacement(b, SeatLayout{});
    return std::hypot(pa.x - pb.x, pa.z - pb.z);
  };
  ASSERT_LT(distance(0, 3), 2.0f);
  ASSERT_GT(distance(0, 2), 2.0f);
  ASSERT_GT(distance(0, 1), 2.0f);
  RoomSettings settings;
  settings.voice.hearing_radius_m = 2.0f;
  Room room(RoomId{1}, "voice", settings, 0.0);
  test::seatMembers(room, 4);
  Effects fx;
  room.update(1.0 / 60.0 + 1e-6, fx);  // a tick places every head
  fx.clear();
  room.onDatagram(voiceFrom(0, 1), seatedEndpoint(0), 0.02, fx);
  const auto got = forwards(fx);
  EXPECT_EQ(got.size(), 1u);
  EXPECT_EQ(got.count(3), 1u);
  EXPECT_EQ(room.voiceStats().out_of_range, 2u);
}

TEST(VoiceForwarding, AtMostMaxSpeakersPerListenerAndTheLoudestTakesOverAfterTheHold) {
  VoiceSettings settings;
  settings.max_speakers = 2;
  settings.hold_s = 0.5;
  VoiceForwarding v(settings);
  for (std::uint32_t id = 1; id <= 4; ++id) v.addMember(id, 0.0);
  v.setHead(1, {0, 1.6f, 0});  // the listener
  v.setHead(2, {1, 1.6f, 0});
  v.setHead(3, {0, 1.6f, 1});
  v.setHead(4, {-1, 1.6f, 0});
  std::vector<std::uint32_t> to;
  auto hears = [&](std::uint32_t speaker, std::uint8_t level, double t) {
    v.route(speaker, level, t, to);
    return std::find(to.begin(), to.end(), 1u) != to.end();
  };
  // 2 and 3 talk (quietly): they fill listener 1's two places; 4 (loud) is left out at first.
  double t = 0.0;
  for (int k = 0; k < 10; ++k, t += 0.02) {
    EXPECT_TRUE(hears(2, 40, t));
    EXPECT_TRUE(hears(3, 45, t));
  }
  EXPECT_FALSE(hears(4, 10, t));
  // Outranking for less than the hold changes nothing; past it, 4 replaces the weakest (3).
  bool switched = false;
  double switched_at = 0.0;
  for (int k = 0; k < 40 && !switched; ++k, t += 0.02) {
    hears(2, 40, t);
    hears(3, 45, t);
    if (hears(4, 10, t)) {
      switched = true;
      switched_at = t;
    }
  }
  ASSERT_TRUE(switched);
  EXPECT_GE(switched_at - 0.2, 0.5 - 0.02 - 1e-9);  // 4 first outranked at t = 0.2
  EXPECT_EQ(v.speakersOf(1), (std::vector<std::uint32_t>{2, 4}));
  EXPECT_EQ(v.stats().replacements, 1u);
  // A speaker silent for silence_s frees its place at once.
  t += 1.0;
  EXPECT_TRUE(hears(3, 45, t));
}

TEST(VoiceForwarding, AFloodIsRateLimitedPerSpeaker) {
  spdlog::set_level(spdlog::level::err);
  Room room(RoomId{1}, "voice", RoomSettings{}, 0.0);
  test::seatMembers(room, 2);
  Effects fx;
  int forwarded = 0;
  for (int k = 0; k < 200; ++k) {  // 200 frames in 0.2 s: 1000/s
    fx.clear();
    room.onDatagram(voiceFrom(0, static_cast<std::uint16_t>(k)), seatedEndpoint(0), 0.001 * k, fx);
    forwarded += static_cast<int>(fx.datagrams.size());
  }
  // The burst (20) and 60/s for 0.2 s (12): about 32 pass.
  EXPECT_LE(forwarded, 34);
  EXPECT_GE(forwarded, 20);
  EXPECT_GT(room.drops().counts().at("voice rate limit"), 150u);
  EXPECT_EQ(room.voiceStats().rate_limited, room.drops().counts().at("voice rate limit"));
}

TEST(VoiceForwarding, MalformedForgedAndDisabledVoiceIsDropped) {
  spdlog::set_level(spdlog::level::err);
  Room room(RoomId{1}, "voice", RoomSettings{}, 0.0);
  test::seatMembers(room, 2);
  Effects fx;
  // An empty payload, sealed properly.
  std::vector<std::uint8_t> plain;
  wire::VoicePacket p;
  p.header.member_id = seatedMemberId(0);
  p.payload = kOpus;
  ASSERT_TRUE(wire::writeVoice(p, plain));
  plain.resize(wire::kVoiceHeaderBytes);
  room.onDatagram(test::sealAs(seatedMemberId(0), plain), seatedEndpoint(0), 0.01, fx);
  EXPECT_EQ(room.drops().counts().at("malformed voice"), 1u);
  // Sealed with another member's key: the tag does not verify.
  std::vector<std::uint8_t> forged;
  ASSERT_TRUE(wire::writeVoice(p, forged));
  room.onDatagram(test::sealAs(seatedMemberId(1), forged), seatedEndpoint(0), 0.02, fx);
  // From the wrong address.
  room.onDatagram(voiceFrom(0, 1), seatedEndpoint(1), 0.03, fx);
  EXPECT_EQ(room.drops().counts().at("wrong endpoint"), 1u);
  EXPECT_TRUE(fx.datagrams.empty());
  EXPECT_EQ(room.drops().total(), 3u);

  RoomSettings off;
  off.voice.enabled = false;
  Room quiet(RoomId{2}, "quiet", off, 0.0);
  test::seatMembers(quiet, 2);
  quiet.onDatagram(voiceFrom(0, 1), seatedEndpoint(0), 0.01, fx);
  EXPECT_TRUE(fx.datagrams.empty());
  EXPECT_EQ(quiet.drops().counts().at("voice disabled"), 1u);
}

TEST(VoiceForwarding, ServerConfigVoiceSection) {
  auto defaults = parseServerConfig("", "test.toml");
  ASSERT_TRUE(defaults);
  EXPECT_TRUE(defaults->voice.enabled);
  EXPECT_EQ(defaults->voice.max_speakers, 6);
  EXPECT_FLOAT_EQ(defaults->voice.hearing_radius_m, 20.0f);
  auto set = parseServerConfig(
      "[voice]\nenabled = false\nhearing_radius_m = 8.5\nmax_speakers = 3\nhold_s = 1.0\n",
      "test.toml");
  ASSERT_TRUE(set) << set.error().message;
  EXPECT_FALSE(set->voice.enabled);
  EXPECT_FLOAT_EQ(set->voice.hearing_radius_m, 8.5f);
  EXPECT_EQ(set->voice.max_speakers, 3);
  EXPECT_DOUBLE_EQ(set->voice.hold_s, 1.0);
  EXPECT_EQ(roomSettings(*set).voice.max_speakers, 3);
  auto unknown = parseServerConfig("[voice]\nloudness = 3\n", "test.toml");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("loudness"), std::string::npos) << unknown.error().message;
  auto range = parseServerConfig("[voice]\nmax_speakers = 65\n", "test.toml");
  ASSERT_FALSE(range);
  EXPECT_NE(range.error().message.find("max_speakers"), std::string::npos) << range.error().message;
  // The shipped config parses and says the same as the defaults.
  auto shipped = loadServerConfig("config/server.toml");
  ASSERT_TRUE(shipped) << shipped.error().message;
  EXPECT_EQ(shipped->voice.max_speakers, 6);
}

}  // namespace
}  // namespace vistel::server
