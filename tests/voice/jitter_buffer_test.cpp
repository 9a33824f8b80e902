// The playout buffer on its own (no codec), in simulated time: delay against jitter,
// reordering, late and duplicate packets, FEC decisions, talkspurts, and clock drift over
// a simulated hour.
#include "common/voice/jitter_buffer.hpp"

#include <algorithm>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "common/voice/voice_link_sim.hpp"

namespace vistel {
namespace {

constexpr int64_t kBufferFrame = kVoiceFrameSamples;
const uint8_t kPayload[1] = {0x42};

struct Arrival {
  double time;  // receiver clock, samples
  uint16_t sequence;
  uint32_t capture;
};

struct RunResult {
  std::vector<double> delay_ms;  // per frame played from a packet: pull - capture (receiver)
  JitterBufferStats stats;
  std::vector<int64_t> jitter_delay;  // the buffer's jitter delay at each pull
};

// Continuous speech for `seconds` from a sender whose clock runs `ppm` fast, delayed by
// uniform [0, jitter_s] and lost with probability `loss`; the receiver pulls every frame.
RunResult run(VoiceJitterBuffer& buffer, double seconds, double jitter_s, double ppm, double loss,
              uint32_t seed, std::vector<size_t> pause_frames = {}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double scale = 1.0 / (1.0 + ppm * 1e-6);
  const size_t frames = static_cast<size_t>(seconds * 50.0);
  std::vector<Arrival> arrivals;
  arrivals.reserve(frames);
  uint16_t sequence = 0;
  for (size_t k = 0; k < frames; ++k) {
    if (std::binary_search(pause_frames.begin(), pause_frames.end(), k)) continue;
    const uint16_t s = sequence++;
    const double jitter = unit(rng) * jitter_s * kVoiceSampleRate;
    if (unit(rng) < loss) continue;
    arrivals.push_back({static_cast<double>((k + 1) * kBufferFrame) * scale + jitter, s,
                        static_cast<uint32_t>(k * kBufferFrame)});
  }
  std::stable_sort(arrivals.begin(), arrivals.end(),
                   [](const Arrival& a, const Arrival& b) { return a.time < b.time; });
  RunResult result;
  size_t next = 0;
  const double end = static_cast<double>(frames * kBufferFrame) * scale + (jitter_s + 0.5) * 48000;
  for (int64_t now = 500; static_cast<double>(now) < end; now += kBufferFrame) {
    for (; next < arrivals.size() && arrivals[next].time <= static_cast<double>(now); ++next) {
      buffer.push({arrivals[next].sequence, arrivals[next].capture, kPayload},
                  static_cast<int64_t>(arrivals[next].time));
    }
    const auto decision = buffer.pull(now);
    if (decision.kind == PlayoutKind::kDecode || decision.kind == PlayoutKind::kFec) {
      result.delay_ms.push_back(
          (static_cast<double>(now) - static_cast<double>(decision.capture_time) * scale) / 48.0);
      result.jitter_delay.push_back(buffer.jitterDelay());
    }
  }
  result.stats = buffer.stats();
  return result;
}

TEST(JitterBuffer, DelayConvergesNearTheJitterPercentile) {
  VoiceJitterBuffer buffer;
  const auto result = run(buffer, 30.0, 0.050, 0.0, 0.0, 5);
  // Uniform 0..50 ms jitter: the 97th percentile is 48.5 ms, plus the 5 ms margin.
  const double jitter_ms = static_cast<double>(buffer.jitterDelay()) / 48.0;
  const std::vector<double> tail(result.delay_ms.end() - 500, result.delay_ms.end());
  // Pull minus capture = the 20 ms of framing + jitter delay + [0, 20 ms) of grid.
  const double p50 = quantile(tail, 0.5), p99 = quantile(tail, 0.99);
  const double late = static_cast<double>(result.stats.late) / (30.0 * 50.0);
  std::printf(
      "50 ms jitter: jitter delay %.1f ms, pull - capture p50 %.1f ms p99 %.1f ms, "
      "late %.2f%%, dropped %lld, inserted %lld\n",
      jitter_ms, p50, p99, 100.0 * late, static_cast<long long>(result.stats.dropped),
      static_cast<long long>(result.stats.inserted));
  EXPECT_NEAR(jitter_ms, 53.5, 4.0);
  EXPECT_GE(quantile(tail, 0.01), 20.0 + jitter_ms - 10.0 - 1.0);
  EXPECT_LE(p99, 20.0 + jitter_ms + 20.0 + 10.0 + 1.0);
  EXPECT_LT(late, 0.05);
}

TEST(JitterBuffer, LoopbackDelayIsTheMarginAlone) {
  VoiceJitterBuffer buffer;
  const auto result = run(buffer, 5.0, 0.0, 0.0, 0.0, 1);
  EXPECT_EQ(buffer.jitterDelay(), buffer.settings().margin_samples);
  EXPECT_LE(quantile(result.delay_ms, 1.0), 20.0 + 5.0 + 20.0);
  EXPECT_EQ(result.stats.decoded, 5 * 50);
  EXPECT_LE(result.stats.concealed, buffer.settings().max_conceal_frames);  // past the end
  EXPECT_EQ(result.stats.late, 0);
}

TEST(JitterBuffer, DelayStaysBoundedWithASenderClock200PpmFastOverAnHour) {
  for (const double ppm : {200.0, -200.0}) {
    VoiceJitterBuffer buffer;
    const auto result = run(buffer, 3600.0, 0.020, ppm, 0.0, 9);
    const std::vector<double> first(result.delay_ms.begin() + 500, result.delay_ms.begin() + 3500);
    const std::vector<double> last(result.delay_ms.end() - 3000, result.delay_ms.end());
    const double first_max = quantile(first, 1.0), last_max = quantile(last, 1.0);
    std::printf(
        "%+.0f ppm over an hour: delay max first minute %.1f ms, last minute %.1f ms, "
        "dropped %lld, inserted %lld, late %lld\n",
        ppm, first_max, last_max, static_cast<long long>(result.stats.dropped),
        static_cast<long long>(result.stats.inserted), static_cast<long long>(result.stats.late));
    // 200 ppm of an hour is 720 ms = 36 frames to drop (fast) or insert (slow).
    EXPECT_LE(last_max, first_max + 12.0);
    EXPECT_GE(quantile(last, 0.0), quantile(first, 0.0) - 12.0);
    if (ppm > 0) {
      EXPECT_NEAR(static_cast<double>(result.stats.dropped), 36.0, 10.0);
    } else {
      EXPECT_NEAR(static_cast<double>(result.stats.inserted), 36.0, 10.0);
    }
    EXPECT_LT(result.stats.late, 3600 * 50 / 100);
  }
}

TEST(JitterBuffer, ReorderedPacketsPlayInSequence) {
  VoiceJitterBuffer buffer;
  // Frames 0..9 arrive as 1 0 3 2 5 4 ..., all before playout starts.
  const int order[10] = {1, 0, 3, 2, 5, 4, 7, 6, 9, 8};
  for (int i = 0; i < 10; ++i) {
    const int k = order[i];
    ASSERT_TRUE(
        buffer.push({static_cast<uint16_t>(k), static_cast<uint32_t>(k * kBufferFrame), kPayload},
                    (k + 1) * kBufferFrame + 100));
  }
  std::vector<int64_t> played;
  for (int64_t now = 2 * kBufferFrame; now < 20 * kBufferFrame; now += kBufferFrame) {
    const auto d = buffer.pull(now);
    if (d.kind == PlayoutKind::kDecode) played.push_back(d.sequence);
  }
  ASSERT_FALSE(played.empty());
  for (size_t i = 1; i < played.size(); ++i) EXPECT_EQ(played[i], played[i - 1] + 1);
  EXPECT_EQ(played.back(), 9);
}

TEST(JitterBuffer, LateAndDuplicatePacketsAreDropped) {
  VoiceJitterBuffer buffer;
  for (int k = 0; k < 5; ++k) {
    ASSERT_TRUE(
        buffer.push({static_cast<uint16_t>(k), static_cast<uint32_t>(k * kBufferFrame), kPayload},
                    (k + 1) * kBufferFrame));
  }
  ASSERT_TRUE(buffer.push({3, 3 * kBufferFrame, kPayload}, 4 * kBufferFrame + 10));
  EXPECT_EQ(buffer.stats().duplicate, 1);
  // Play a few frames, then offer frame 1 again (late).
  for (int64_t now = kBufferFrame + 300; now < 5 * kBufferFrame; now += kBufferFrame)
    (void)buffer.pull(now);
  ASSERT_TRUE(buffer.push({1, 1 * kBufferFrame, kPayload}, 5 * kBufferFrame));
  EXPECT_EQ(buffer.stats().late, 1);
  // Empty and oversized payloads are refused.
  EXPECT_FALSE(buffer.push({6, 6 * kBufferFrame, {}}, 6 * kBufferFrame));
  const std::vector<uint8_t> huge(kVoiceMaxPacketBytes + 1, 0);
  EXPECT_FALSE(buffer.push({6, 6 * kBufferFrame, huge}, 6 * kBufferFrame));
  EXPECT_EQ(buffer.stats().invalid, 2);
}

TEST(JitterBuffer, AMissingFrameUsesFecFromTheNextElseConcealment) {
  VoiceJitterBuffer buffer;
  // Frames 0..9 except 3 (next one present: FEC) and 6, 7 (6's next is missing: conceal).
  for (int k = 0; k < 10; ++k) {
    if (k == 3 || k == 6 || k == 7) continue;
    const uint8_t payload[1] = {static_cast<uint8_t>(k)};
    ASSERT_TRUE(
        buffer.push({static_cast<uint16_t>(k), static_cast<uint32_t>(k * kBufferFrame), payload},
                    (k + 1) * kBufferFrame));
  }
  std::vector<PlayoutDecision> decisions;
  std::vector<uint8_t> first_byte;
  for (int64_t now = kBufferFrame + 300; now < 12 * kBufferFrame; now += kBufferFrame) {
    const auto d = buffer.pull(now);
    if (d.sequence >= 0) {
      decisions.push_back(d);
      first_byte.push_back(d.packet.empty() ? 0xFF : d.packet[0]);
    }
  }
  // Frame 10 is concealed past the end (nothing says the talkspurt is over yet).
  ASSERT_GE(decisions.size(), 10u);
  EXPECT_EQ(decisions[3].kind, PlayoutKind::kFec);
  EXPECT_EQ(first_byte[3], 4);  // frame 3 recovered from packet 4
  EXPECT_EQ(decisions[4].kind, PlayoutKind::kDecode);
  EXPECT_EQ(decisions[6].kind, PlayoutKind::kConceal);
  EXPECT_EQ(decisions[7].kind, PlayoutKind::kFec);
  EXPECT_EQ(decisions[9].kind, PlayoutKind::kDecode);
}

TEST(JitterBuffer, TalkspurtsRealignInSilenceAndSequencesWrap) {
  // Pauses of 1 s every 10 s (the sender sends nothing), a sender 200 ppm fast.
  VoiceJitterBuffer buffer;
  std::vector<size_t> pauses;
  for (size_t k = 0; k < 60 * 50; ++k) {
    if (k % 500 >= 450) pauses.push_back(k);
  }
  const auto result = run(buffer, 60.0, 0.030, 200.0, 0.0, 11, pauses);
  EXPECT_GE(result.stats.talkspurts, 6);
  // Concealment runs on past each talkspurt's last packet, and fills in for late packets.
  EXPECT_LE(result.stats.concealed,
            result.stats.talkspurts * buffer.settings().max_conceal_frames + result.stats.late);
  EXPECT_LT(result.stats.late, 60 * 50 / 50);
  EXPECT_LT(quantile(result.delay_ms, 1.0), 20.0 + 40.0 + 20.0 + 10.0);

  // Sequence numbers that wrap from 65535 to 0 play on.
  VoiceJitterBuffer wrap;
  for (int k = 0; k < 6; ++k) {
    const uint16_t sequence = static_cast<uint16_t>(65533 + k);
    ASSERT_TRUE(wrap.push({sequence, static_cast<uint32_t>(k * kBufferFrame), kPayload},
                          (k + 1) * kBufferFrame));
  }
  int decoded = 0;
  for (int64_t now = kBufferFrame + 300; now < 10 * kBufferFrame; now += kBufferFrame) {
    decoded += wrap.pull(now).kind == PlayoutKind::kDecode ? 1 : 0;
  }
  EXPECT_EQ(decoded, 6);
}

TEST(JitterBuffer, AForwardingGapEndsTheTalkspurtInsteadOfConcealingIt) {
  // Frames 0..19 arrive, then the server skips this speaker for 50 frames (2..3 s of
  // speech it did not forward), then frames 70..89 arrive on time.
  VoiceJitterBuffer buffer;
  std::vector<PlayoutDecision> played;
  std::vector<int64_t> offsets;  // pull - capture of each decoded frame
  int concealed_run = 0, longest_concealed_run = 0;
  for (int64_t tick = 0; tick < 100; ++tick) {
    const int64_t now = tick * kBufferFrame + 300;
    const int64_t k = tick - 1;  // the frame that has just arrived
    if (k >= 0 && (k < 20 || (k >= 70 && k < 90))) {
      ASSERT_TRUE(buffer.push(
          {static_cast<uint16_t>(k), static_cast<uint32_t>(k * kBufferFrame), kPayload}, now - 10));
    }
    const auto d = buffer.pull(now);
    concealed_run = d.kind == PlayoutKind::kConceal ? concealed_run + 1 : 0;
    longest_concealed_run = std::max(longest_concealed_run, concealed_run);
    if (d.kind == PlayoutKind::kDecode) {
      played.push_back(d);
      offsets.push_back(now - d.capture_time);
    }
  }
  EXPECT_LE(longest_concealed_run, buffer.settings().max_conceal_frames);
  ASSERT_EQ(played.size(), 40u);
  EXPECT_EQ(played[20].sequence, 70);
  // The second talkspurt plays with the same delay as the first.
  for (const auto& d : played) EXPECT_EQ(offsets[&d - played.data()], offsets[0]);
}

}  // namespace
}  // namespace vistel
