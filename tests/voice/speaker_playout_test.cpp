// A speaker's receive side and the send side per frame: no heap allocation once warm,
// and a corrupt packet from the network is concealed, counted and survived.
#include "common/voice/speaker_playout.hpp"

#include <gtest/gtest.h>

#include "common/voice/mixer.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/voice/voice_activity.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

constexpr int64_t kPlayoutFrame = kVoiceFrameSamples;

TEST(SpeakerPlayout, SendAndReceivePerFrameAllocateNothingOnceWarm) {
  const auto speech = synthesizeSpeech(2.0, {.pauses = false});
  auto encoder = OpusVoiceEncoder::create({});
  auto vad = VoiceActivity::create();
  ASSERT_TRUE(encoder.ok() && vad.ok());
  std::vector<SpeakerPlayout> speakers;
  for (int s = 0; s < 16; ++s) speakers.push_back(std::move(*SpeakerPlayout::create()));
  std::vector<SpatialSourceState> states(16);
  VoiceMixer mixer;
  std::vector<float> frame(kVoiceFrameSamples), mono(kVoiceFrameSamples);
  std::vector<float> out(2 * kVoiceFrameSamples);
  std::vector<uint8_t> packet(kVoiceMaxPacketBytes);

  auto tick = [&](int64_t k) {
    // Send: capture, VAD, encode.
    std::copy_n(speech.begin() + (k % 90) * kPlayoutFrame, kPlayoutFrame, frame.begin());
    (void)vad->process(frame);
    auto size = encoder->encode(frame, packet);
    // Receive: every speaker's packet, then the playout tick and the mix.
    const std::span<const uint8_t> bytes(packet.data(), size.ok() ? *size : 0);
    mixer.beginBlock();
    for (int s = 0; s < 16; ++s) {
      if (k % 10 != 3) {  // every 10th packet lost
        speakers[s].push(
            {static_cast<uint16_t>(k), static_cast<uint32_t>(k * kPlayoutFrame), bytes},
            (k + 1) * kPlayoutFrame);
      }
      speakers[s].pull((k + 1) * kPlayoutFrame + 300, mono);
      mixer.addSpeaker(HeadPose{}, {0.3f * s - 2.0f, 0.0f, 1.5f}, mono, states[s]);
    }
    mixer.finishBlock(out);
  };
  for (int64_t k = 0; k < 20; ++k) tick(k);  // warm-up
  test::AllocationCounter counter;
  for (int64_t k = 20; k < 90; ++k) tick(k);
  EXPECT_EQ(counter.count(), 0);
  EXPECT_GT(speakers[0].buffer().stats().concealed, 0);  // the losses took the PLC path
}

TEST(SpeakerPlayout, ACorruptPacketIsConcealedAndCounted) {
  auto playout = SpeakerPlayout::create();
  ASSERT_TRUE(playout.ok());
  auto encoder = OpusVoiceEncoder::create({});
  ASSERT_TRUE(encoder.ok());
  const auto speech = synthesizeSpeech(0.5, {.pauses = false});
  std::vector<uint8_t> packet(kVoiceMaxPacketBytes);
  std::vector<float> out(kVoiceFrameSamples);
  int decoded = 0;
  for (int64_t k = 0; k < 20; ++k) {
    auto size = encoder->encode(
        std::span<const float>(speech.data() + k * kPlayoutFrame, kVoiceFrameSamples), packet);
    ASSERT_TRUE(size.ok());
    // Frame 5 arrives as a 10 ms CELT packet: valid Opus, wrong for this pipeline.
    std::vector<uint8_t> bytes(packet.begin(), packet.begin() + static_cast<long>(*size));
    if (k == 5) bytes = {static_cast<uint8_t>(16u << 3), 0x00, 0x00};
    ASSERT_TRUE(
        playout->push({static_cast<uint16_t>(k), static_cast<uint32_t>(k * kPlayoutFrame), bytes},
                      (k + 1) * kPlayoutFrame));
    const auto decision = playout->pull((k + 1) * kPlayoutFrame + 300, out);
    decoded += decision.kind == PlayoutKind::kDecode ? 1 : 0;
    for (float x : out) ASSERT_TRUE(std::isfinite(x));
  }
  EXPECT_EQ(playout->decodeErrors(), 1);
  EXPECT_GE(decoded, 18);
}

}  // namespace
}  // namespace vistel
