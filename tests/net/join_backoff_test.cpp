// JoinBackoff (client/net/join_backoff.hpp): windows that double from the server's hint
// up to the cap, delays in the upper half of each window, spread across a crowd, and a
// limit on refusals in a row.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "client/net/join_backoff.hpp"

namespace vistel::net {
namespace {

TEST(JoinBackoff, WindowsDoubleFromTheHintUpToTheCap) {
  BackoffSettings settings;
  settings.base_s = 0.5;
  settings.max_s = 6.0;
  settings.max_attempts = 10;
  JoinBackoff backoff(settings, 7);
  double window = 1.0;  // the hint exceeds the base
  for (int k = 0; k < 10; ++k) {
    const double delay = backoff.nextDelay(1.0);
    EXPECT_GE(delay, 0.5 * window - 1e-12) << k;
    EXPECT_LE(delay, window + 1e-12) << k;
    window = std::min(6.0, window * 2.0);
  }
  EXPECT_LT(backoff.nextDelay(1.0), 0.0);  // the eleventh refusal: give up
  backoff.reset();
  EXPECT_GE(backoff.nextDelay(0.1), 0.25);  // the base when the hint is smaller
}

TEST(JoinBackoff, ACrowdRefusedAtOnceComesBackSpreadOut) {
  std::vector<double> delays;
  for (int i = 0; i < 100; ++i) {
    JoinBackoff backoff(BackoffSettings{}, static_cast<std::uint64_t>(1000 + i));
    delays.push_back(backoff.nextDelay(1.0));
  }
  std::sort(delays.begin(), delays.end());
  EXPECT_GE(delays.front(), 0.5);
  EXPECT_LE(delays.back(), 1.0);
  // Spread over the window's upper half, not bunched: each tenth of it holds some.
  for (int bin = 0; bin < 5; ++bin) {
    const double lo = 0.5 + 0.1 * bin;
    const auto in = std::count_if(delays.begin(), delays.end(),
                                  [&](double d) { return d >= lo && d < lo + 0.1; });
    EXPECT_GE(in, 8) << "delays in [" << lo << ", " << lo + 0.1 << ")";
  }
}

TEST(JoinBackoff, ZeroAttemptsNeverRetries) {
  BackoffSettings settings;
  settings.max_attempts = 0;
  JoinBackoff backoff(settings, 1);
  EXPECT_LT(backoff.nextDelay(1.0), 0.0);
}

}  // namespace
}  // namespace vistel::net
