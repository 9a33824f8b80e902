// The delta-coded uplink (proto/WIRE.md §3.4, common/wire/posture_delta.hpp) end to end:
// a member's postures cost a fraction of a keyframe, and on a lossy uplink a lost datagram
// costs that posture alone, because deltas refer to what the server acknowledged.
#include <cstdio>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel {
namespace {

using net::SessionState;
using test::SimLink;
using test::SimNetwork;

TEST(PostureUplink, DeltasOnALossyLinkCostTheirOwnLossOnly) {
  spdlog::set_level(spdlog::level::err);
  server::ServerConfig config;
  config.tick_rate_hz = 60.0;
  SimNetwork net(config, 77);
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
  SimLink lossy;
  lossy.latency = 0.015;
  lossy.jitter = 0.010;  // reorders
  lossy.loss = 0.10;
  const auto sender = net.addClient(test::sessionFor("up", "sender", avatar, 5), lossy, {});
  const auto viewer = net.addClient(test::sessionFor("up", "viewer", avatar, 5));
  net.connect(sender);
  net.connect(viewer);
  net.advance(1.0);
  ASSERT_EQ(net.session(sender).state(), SessionState::kLive) << net.session(sender).error();

  std::uint64_t sent = 0;
  double next = net.now();
  net.advance(10.0, 0.001, [&](double now) {
    if (now + 1e-9 < next) return;
    next += 1.0 / 60.0;
    if (net.session(sender).sendPosture(test::syntheticPosture(now), net.localTime(sender))) {
      ++sent;
    }
  });
  net.advance(0.2);

  const auto& up = net.session(sender).stats();
  const double bytes_per_posture =
      static_cast<double>(up.posture_bytes_sent) / static_cast<double>(up.postures_sent);
  const std::size_t keyframe = wire::kClientHeaderBytes + 1 + 13 + 5 * 4;
  const auto& heard = net.session(viewer).stats().members.at("sender");
  const server::Room* room = net.server().findRoom("up");
  ASSERT_NE(room, nullptr);
  std::printf(
      "[ measure  ] %llu postures sent at 10%% loss: %.1f bytes each sealed (keyframe %zu "
      "unsealed), %llu "
      "received, %llu without their reference\n",
      static_cast<unsigned long long>(sent), bytes_per_posture, keyframe,
      static_cast<unsigned long long>(heard.postures_received),
      static_cast<unsigned long long>(room->posturesWithoutReference()));
  // The codec's share (the seal adds the same 16 bytes to every datagram, WIRE.md §3.9).
  EXPECT_LT(bytes_per_posture - static_cast<double>(wire::kSealOverheadBytes),
            0.7 * static_cast<double>(keyframe));
  // About 10% lost on the way; nearly none of the rest refused for a missing reference.
  EXPECT_GE(static_cast<double>(heard.postures_received), 0.85 * static_cast<double>(sent));
  EXPECT_LE(static_cast<double>(room->posturesWithoutReference()),
            0.02 * static_cast<double>(sent));
}

}  // namespace
}  // namespace vistel
