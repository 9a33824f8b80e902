// The network simulator's pure core: the spec parser (good specs, and bad ones whose
// errors name the item), and one direction's behaviour with a fixed seed and a fake
// clock — loss rate, delay bounds, duplication, reordering, bytes unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "client/net/client_config.hpp"
#include "client/net/net_sim.hpp"

namespace vistel::net {
namespace {

TEST(NetSimSpec, ParsesTheIssueExample) {
  auto spec = parseNetSimSpec("loss=0.1,latency=30ms,jitter=50ms,dup=0.01,reorder=0.02");
  ASSERT_TRUE(spec) << spec.error().message;
  EXPECT_DOUBLE_EQ(spec->loss, 0.1);
  EXPECT_DOUBLE_EQ(spec->latency_s, 0.03);
  EXPECT_DOUBLE_EQ(spec->jitter_s, 0.05);
  EXPECT_DOUBLE_EQ(spec->dup, 0.01);
  EXPECT_DOUBLE_EQ(spec->reorder, 0.02);
  EXPECT_EQ(spec->jitter_dist, JitterDistribution::kUniform);
  EXPECT_EQ(spec->direction, NetSimDirection::kBoth);
  EXPECT_EQ(spec->seed, 0u);
  EXPECT_TRUE(spec->active());
}

TEST(NetSimSpec, ParsesUnitsPercentagesAndEveryKey) {
  auto spec = parseNetSimSpec(
      " loss = 5% , latency=0.25s, jitter=500us, jitter_dist=normal, dup=0, reorder=1, "
      "reorder_delay=7ms, dir=in, seed=18446744073709551615 ");
  ASSERT_TRUE(spec) << spec.error().message;
  EXPECT_DOUBLE_EQ(spec->loss, 0.05);
  EXPECT_DOUBLE_EQ(spec->latency_s, 0.25);
  EXPECT_DOUBLE_EQ(spec->jitter_s, 0.0005);
  EXPECT_EQ(spec->jitter_dist, JitterDistribution::kNormal);
  EXPECT_DOUBLE_EQ(spec->reorder, 1.0);
  EXPECT_DOUBLE_EQ(spec->reorder_delay_s, 0.007);
  EXPECT_EQ(spec->direction, NetSimDirection::kIn);
  EXPECT_EQ(spec->seed, 18446744073709551615ull);
  EXPECT_TRUE(spec->appliesIn());
  EXPECT_FALSE(spec->appliesOut());

  // Written back and read again, the same.
  auto again = parseNetSimSpec(describeNetSim(*spec));
  ASSERT_TRUE(again) << describeNetSim(*spec) << ": " << again.error().message;
  EXPECT_EQ(describeNetSim(*again), describeNetSim(*spec));
}

TEST(NetSimSpec, EmptyAndOffMeanNoSimulation) {
  for (const char* text : {"", "  ", "off", "loss=0,latency=0ms"}) {
    auto spec = parseNetSimSpec(text);
    ASSERT_TRUE(spec) << text;
    EXPECT_FALSE(spec->active()) << text;
    EXPECT_EQ(describeNetSim(*spec), "off");
  }
}

TEST(NetSimSpec, BadSpecsNameTheItem) {
  struct Case {
    const char* text;
    const char* expected;  // a part of the message
  };
  const Case cases[] = {
      {"loss=2", "loss='2': expected a probability"},
      {"loss=-0.1", "loss='-0.1'"},
      {"loss=abc", "loss='abc'"},
      {"loss=", "loss=''"},
      {"loss=150%", "loss='150%'"},
      {"latency=30", "latency='30': expected a duration"},
      {"latency=30 ms", "latency='30 ms'"},
      {"latency=11s", "latency='11s'"},
      {"jitter=-5ms", "jitter='-5ms'"},
      {"jitter=fast", "jitter='fast'"},
      {"jitter_dist=gauss", "jitter_dist='gauss': expected uniform or normal"},
      {"dir=up", "dir='up': expected both, in or out"},
      {"seed=-1", "seed='-1'"},
      {"seed=99999999999999999999", "seed="},
      {"lose=0.1", "unknown key 'lose'"},
      {"loss", "'loss' is not KEY=VALUE"},
      {"loss=0.1,,dup=0.1", "an empty item"},
      {"loss=0.1,", "an empty item"},
      {"loss=0.1,loss=0.2", "'loss' is given twice"},
      {"latency=nanms", "latency='nanms'"},
      {"latency=infs", "latency='infs'"},
  };
  for (const Case& c : cases) {
    auto spec = parseNetSimSpec(c.text);
    ASSERT_FALSE(spec) << c.text;
    EXPECT_NE(spec.error().message.find(c.expected), std::string::npos)
        << c.text << " -> " << spec.error().message;
    EXPECT_EQ(spec.error().message.rfind("--netsim '", 0), 0u) << spec.error().message;
  }
}

TEST(NetSimSpec, TheClientConfigChecksItsKey) {
  auto good = parseClientConfig("[network]\nnetsim = \"loss=0.1,jitter=20ms\"\n", "t.toml");
  ASSERT_TRUE(good) << good.error().message;
  EXPECT_EQ(good->netsim, "loss=0.1,jitter=20ms");
  EXPECT_DOUBLE_EQ(good->max_extrapolation_s, 0.1);
  auto bad = parseClientConfig("[network]\nnetsim = \"loss=3\"\n", "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("t.toml: [network] netsim 'loss=3': loss='3'"),
            std::string::npos)
      << bad.error().message;
  auto extrapolation = parseClientConfig("[playback]\nmax_extrapolation_s = 0\n", "t.toml");
  ASSERT_TRUE(extrapolation) << extrapolation.error().message;
  EXPECT_DOUBLE_EQ(extrapolation->max_extrapolation_s, 0.0);
  EXPECT_FALSE(parseClientConfig("[playback]\nmax_extrapolation_s = 2\n", "t.toml"));
}

// A datagram numbered i (4 bytes, little endian) followed by a pattern.
std::vector<std::uint8_t> datagram(std::uint32_t i) {
  std::vector<std::uint8_t> d(24);
  for (int b = 0; b < 4; ++b)
    d[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(i >> (8 * b));
  for (std::size_t k = 4; k < d.size(); ++k) d[k] = static_cast<std::uint8_t>(k * 37 + i);
  return d;
}
std::uint32_t numberOf(const std::vector<std::uint8_t>& d) {
  std::uint32_t i = 0;
  for (int b = 0; b < 4; ++b)
    i |= static_cast<std::uint32_t>(d[static_cast<std::size_t>(b)]) << (8 * b);
  return i;
}

struct Arrival {
  std::uint32_t number;
  double sent;
  double arrived;
};

// Sends n datagrams one every `interval` s from t = 0 and collects them as they fall due,
// polling every 0.5 ms; checks each arrives byte for byte as sent.
std::vector<Arrival> run(NetSimLink& link, int n, double interval) {
  std::vector<Arrival> arrivals;
  std::vector<std::uint8_t> out;
  int sent = 0;
  for (double now = 0.0; sent < n || link.inFlight() > 0; now += 0.0005) {
    while (sent < n && static_cast<double>(sent) * interval <= now) {
      link.push(datagram(static_cast<std::uint32_t>(sent)), static_cast<double>(sent) * interval);
      ++sent;
    }
    while (link.pop(now, out)) {
      const std::uint32_t i = numberOf(out);
      EXPECT_EQ(out, datagram(i));
      arrivals.push_back({i, static_cast<double>(i) * interval, now});
    }
  }
  return arrivals;
}

TEST(NetSimLink, LosesAboutTheRequestedShare) {
  NetSimSpec spec;
  spec.loss = 0.1;
  NetSimLink link(spec, 42);
  const int n = 20000;
  const auto arrivals = run(link, n, 0.001);
  const double lost = 1.0 - static_cast<double>(arrivals.size()) / n;
  EXPECT_NEAR(lost, 0.1, 0.01);  // 0.1 +- 4.7 standard deviations
  EXPECT_EQ(link.counters().offered, static_cast<std::uint64_t>(n));
  EXPECT_EQ(link.counters().lost + link.counters().delivered, static_cast<std::uint64_t>(n));
  // No delay asked: everything due at once, in order.
  for (std::size_t k = 1; k < arrivals.size(); ++k) {
    EXPECT_LT(arrivals[k - 1].number, arrivals[k].number);
  }
}

TEST(NetSimLink, DelaysWithinLatencyPlusUniformJitter) {
  NetSimSpec spec;
  spec.latency_s = 0.03;
  spec.jitter_s = 0.05;
  NetSimLink link(spec, 7);
  const auto arrivals = run(link, 4000, 0.002);
  ASSERT_EQ(arrivals.size(), 4000u);
  double sum = 0.0;
  double lo = 1e9;
  double hi = 0.0;
  for (const Arrival& a : arrivals) {
    const double d = a.arrived - a.sent;
    sum += d;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  // Polled every 0.5 ms: arrivals are at most that late.
  EXPECT_GE(lo, 0.03);
  EXPECT_LT(lo, 0.0310);
  EXPECT_LE(hi, 0.0805);
  EXPECT_GT(hi, 0.0790);
  EXPECT_NEAR(sum / 4000.0, 0.03 + 0.025 + 0.00025, 0.002);  // uniform mean, half a poll
  // Jitter larger than the send interval reorders.
  int inversions = 0;
  for (std::size_t k = 1; k < arrivals.size(); ++k) {
    inversions += arrivals[k - 1].number > arrivals[k].number ? 1 : 0;
  }
  EXPECT_GT(inversions, 100);
}

TEST(NetSimLink, NormalJitterIsHalfNormal) {
  NetSimSpec spec;
  spec.jitter_s = 0.02;
  spec.jitter_dist = JitterDistribution::kNormal;
  NetSimLink link(spec, 9);
  const auto arrivals = run(link, 4000, 0.001);
  double sum = 0.0;
  int beyond_two_scales = 0;
  for (const Arrival& a : arrivals) {
    const double d = a.arrived - a.sent;
    sum += d;
    beyond_two_scales += d > 0.04 + 0.0005 ? 1 : 0;
  }
  EXPECT_NEAR(sum / 4000.0, 0.02 * 0.7979 + 0.00025, 0.0015);  // sigma sqrt(2 / pi)
  EXPECT_NEAR(beyond_two_scales / 4000.0, 0.0455, 0.015);
}

TEST(NetSimLink, DuplicatesAboutTheRequestedShare) {
  NetSimSpec spec;
  spec.dup = 0.05;
  spec.latency_s = 0.001;
  NetSimLink link(spec, 3);
  const int n = 10000;
  const auto arrivals = run(link, n, 0.001);
  const auto copies = arrivals.size() - static_cast<std::size_t>(n);
  EXPECT_EQ(copies, link.counters().duplicated);
  EXPECT_NEAR(static_cast<double>(copies) / n, 0.05, 0.01);
  // Every datagram arrived once or twice.
  std::vector<int> seen(static_cast<std::size_t>(n), 0);
  for (const Arrival& a : arrivals) ++seen[a.number];
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 0), 0);
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 2), static_cast<long>(copies));
}

TEST(NetSimLink, ReorderHoldsBackAShareThatLaterDatagramsOvertake) {
  NetSimSpec spec;
  spec.reorder = 0.1;
  spec.reorder_delay_s = 0.005;
  spec.latency_s = 0.01;
  NetSimLink link(spec, 11);
  const int n = 10000;
  const auto arrivals = run(link, n, 0.001);
  ASSERT_EQ(arrivals.size(), static_cast<std::size_t>(n));
  EXPECT_NEAR(static_cast<double>(link.counters().reordered) / n, 0.1, 0.015);
  // Held back ones arrive latency + 5 ms after sending, the rest after the latency; a held
  // back datagram is overtaken by the ones sent in the 5 ms after it (unless they are held
  // back too).
  int late = 0;
  for (const Arrival& a : arrivals) {
    const double d = a.arrived - a.sent;
    if (d > 0.0125) {
      ++late;
      EXPECT_NEAR(d, 0.015, 0.0006);
    } else {
      EXPECT_NEAR(d, 0.010, 0.0006);
    }
  }
  EXPECT_EQ(static_cast<std::uint64_t>(late), link.counters().reordered);
  int overtaken = 0;
  std::uint32_t highest = 0;
  for (const Arrival& a : arrivals) {
    if (a.number < highest) ++overtaken;
    highest = std::max(highest, a.number);
  }
  EXPECT_GT(overtaken, static_cast<int>(link.counters().reordered) * 8 / 10);
  EXPECT_LE(overtaken, static_cast<int>(link.counters().reordered));
}

TEST(NetSimLink, SameSeedSameFate) {
  NetSimSpec spec;
  spec.loss = 0.2;
  spec.jitter_s = 0.01;
  spec.dup = 0.1;
  spec.reorder = 0.1;
  NetSimLink a(spec, 5);
  NetSimLink b(spec, 5);
  NetSimLink c(spec, 6);
  const auto ra = run(a, 2000, 0.001);
  const auto rb = run(b, 2000, 0.001);
  const auto rc = run(c, 2000, 0.001);
  ASSERT_EQ(ra.size(), rb.size());
  for (std::size_t k = 0; k < ra.size(); ++k) {
    EXPECT_EQ(ra[k].number, rb[k].number);
    EXPECT_DOUBLE_EQ(ra[k].arrived, rb[k].arrived);
  }
  EXPECT_NE(a.counters().lost, c.counters().lost);
}

TEST(NetSimLink, BoundsWhatIsInFlightAndClears) {
  NetSimSpec spec;
  spec.latency_s = 1.0;
  NetSimLink link(spec, 1);
  for (std::size_t i = 0; i < NetSimLink::kMaxQueued + 10; ++i) link.push(datagram(1), 0.0);
  EXPECT_EQ(link.inFlight(), NetSimLink::kMaxQueued);
  EXPECT_EQ(link.counters().overflowed, 10u);
  double due = 0.0;
  ASSERT_TRUE(link.nextDue(due));
  EXPECT_DOUBLE_EQ(due, 1.0);
  std::vector<std::uint8_t> out;
  EXPECT_FALSE(link.pop(0.99, out));
  link.clear();
  EXPECT_EQ(link.inFlight(), 0u);
  EXPECT_FALSE(link.nextDue(due));
}

TEST(NetSimSeed, MixesTheNameAndRepeats) {
  NetSimSpec spec;
  spec.seed = 17;
  EXPECT_EQ(netSimSeed(spec, "bot-1"), netSimSeed(spec, "bot-1"));
  EXPECT_NE(netSimSeed(spec, "bot-1"), netSimSeed(spec, "bot-2"));
}

}  // namespace
}  // namespace vistel::net
