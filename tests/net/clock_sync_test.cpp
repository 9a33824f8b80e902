// The clock-offset estimate: smallest round trip wins.
#include <random>

#include <gtest/gtest.h>

#include "client/net/clock_sync.hpp"

namespace vistel::net {
namespace {

// Simulated pings: local clock = server clock - offset; each direction has a base
// latency and its own random queueing delay.
double runPings(double true_offset, double up_base, double up_jitter, double down_base,
                double down_jitter, int pings, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ClockSync clock(16);
  double local = 10.0;
  for (int i = 0; i < pings; ++i) {
    const double t0 = local;
    const double server = t0 + true_offset + up_base + up_jitter * u(rng);
    const double t3 = server - true_offset + down_base + down_jitter * u(rng);
    clock.addSample(t0, server, t3);
    local = t3 + 0.05;
  }
  return clock.offset();
}

TEST(ClockSync, AsymmetricQueueingIsFilteredOut) {
  // 20 ms base each way; up to 40 ms of queueing upstream, 5 ms downstream.
  const double offset = runPings(123.456, 0.020, 0.040, 0.020, 0.005, 16, 1);
  EXPECT_NEAR(offset, 123.456, 0.003);
}

TEST(ClockSync, BaseAsymmetryLeavesHalfItsDifference) {
  // 10 ms up, 30 ms down, no queueing: the estimate is off by (10 - 30) / 2 ms, the
  // documented limit of any ping-based estimate.
  const double offset = runPings(-5.0, 0.010, 0.0, 0.030, 0.0, 8, 2);
  EXPECT_NEAR(offset, -5.0 - 0.010, 1e-9);
}

TEST(ClockSync, SeedIsUsedUntilTheFirstSampleAndBadSamplesIgnored) {
  ClockSync clock;
  clock.seed(100.0, 1.0);
  EXPECT_DOUBLE_EQ(clock.offset(), 99.0);
  EXPECT_FALSE(clock.synced());
  clock.addSample(2.0, 50.0, 1.0);  // t3 < t0
  EXPECT_FALSE(clock.synced());
  clock.addSample(2.0, 101.01, 2.02);
  EXPECT_TRUE(clock.synced());
  EXPECT_NEAR(clock.offset(), 99.0, 1e-9);
  EXPECT_NEAR(clock.roundTrip(), 0.02, 1e-12);
}

}  // namespace
}  // namespace vistel::net
