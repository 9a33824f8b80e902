// The UDP handshake's challenge (proto/WIRE.md §3.2) over a link slower than the hello
// interval: hellos retried while the first challenge travels get the same cookie, so the
// client's echo binds its address instead of chasing a new challenge every retry.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel {
namespace {

using test::SimNetwork;

TEST(SlowHandshake, ARoundTripLongerThanTheHelloIntervalStillBinds) {
  spdlog::set_level(spdlog::level::err);
  server::ServerConfig config;
  SimNetwork net(config, 91);
  test::SimLink slow;
  slow.latency = 0.2;  // 0.4 s round trip against hellos every 0.1 s
  slow.jitter = 0.05;
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
  const auto far = net.addClient(test::sessionFor("slow", "far", avatar, 5), slow, slow);
  net.connect(far);
  net.advance(2.0);
  EXPECT_EQ(net.session(far).state(), net::SessionState::kLive) << net.session(far).error();
}

}  // namespace
}  // namespace vistel
