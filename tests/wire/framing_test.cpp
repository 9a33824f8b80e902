// Length framing of the TCP control channel.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/framing.hpp"

namespace vistel::wire {
namespace {

TEST(Framing, FramesSurviveArbitrarySplits) {
  std::vector<std::vector<std::uint8_t>> payloads = {
      {}, {1}, {2, 3, 4}, std::vector<std::uint8_t>(5000, 7)};
  std::vector<std::uint8_t> stream;
  for (const auto& p : payloads) appendFrame(p, stream);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    FrameDecoder d(10000);
    std::vector<std::vector<std::uint8_t>> got;
    std::size_t pos = 0;
    while (pos < stream.size()) {
      const std::size_t n = std::min<std::size_t>(stream.size() - pos, 1 + rng() % 700);
      ASSERT_TRUE(d.push(std::span(stream.data() + pos, n)));
      pos += n;
      while (auto f = d.next()) got.emplace_back(f->begin(), f->end());
    }
    EXPECT_EQ(got, payloads);
    EXPECT_EQ(d.buffered(), 0u);
  }
}

TEST(Framing, OversizedLengthBreaksTheStreamAtOnce) {
  FrameDecoder d(1000);
  const std::uint8_t header[4] = {0xE9, 0x03, 0x00, 0x00};  // 1001
  EXPECT_TRUE(d.push(std::span(header, 2)));
  EXPECT_FALSE(d.push(std::span(header + 2, 2)));
  EXPECT_TRUE(d.broken());
  EXPECT_NE(d.error().find("1001"), std::string::npos);
  EXPECT_FALSE(d.next().has_value());
  const std::uint8_t more[1] = {0};
  EXPECT_FALSE(d.push(more));
}

TEST(Framing, OversizedFrameAfterAValidOneIsSeen) {
  std::vector<std::uint8_t> stream;
  appendFrame(std::vector<std::uint8_t>{1, 2}, stream);
  const std::uint8_t big[4] = {0xFF, 0xFF, 0xFF, 0xFF};
  stream.insert(stream.end(), big, big + 4);
  FrameDecoder d(100);
  EXPECT_TRUE(d.push(std::span(stream.data(), 6)));
  ASSERT_TRUE(d.next().has_value());
  EXPECT_FALSE(d.push(std::span(stream.data() + 6, 4)));
  EXPECT_TRUE(d.broken());
}

}  // namespace
}  // namespace vistel::wire
