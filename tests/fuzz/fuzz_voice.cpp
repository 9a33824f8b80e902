// libFuzzer target: the voice datagrams (common/wire/voice_packets.hpp, proto/WIRE.md §3.10)
// and what a listener does with their payload (common/voice: the playout buffer and the
// Opus decoder), on arbitrary bytes. Each input is read:
//   - as a Voice and as a VoiceForward datagram: an accepted one writes back to exactly the
//     same bytes, its payload is 1..400 bytes and its level 0..127, peekPacketType agrees;
//     a refused one says why (a non-empty message naming the datagram);
//   - as a stream of forwarded frames for one speaker: the input's bytes cut into (sequence,
//     capture time, payload) records pushed into a SpeakerPlayout and pulled on the playout
//     grid, so that decode, FEC recovery and concealment run on hostile payloads: every
//     pulled frame is 960 finite samples (libopus's float output may pass +-1), and mixed
//     (spatialiser, limiter) it stays within the limiter's ceiling; nothing reads outside
//     its buffers.
// Seeds: voice datagrams written by the codec (with real Opus packets) and a frame stream.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/voice/mixer.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/speaker_playout.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/wire/voice_packets.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using namespace vistel::wire;
using fuzz::check;

// Real Opus packets of synthetic speech, for the seeds.
std::vector<std::vector<std::uint8_t>> opusPackets(int count) {
  std::vector<std::vector<std::uint8_t>> out;
  auto encoder = OpusVoiceEncoder::create({});
  check(encoder.ok(), "the seed encoder is made");
  const std::vector<float> speech = synthesizeSpeech(0.02 * count, {});
  std::vector<std::uint8_t> packet(kVoiceMaxPacketBytes);
  for (int i = 0; i < count; ++i) {
    const auto frame = std::span(speech).subspan(static_cast<std::size_t>(i) * kVoiceFrameSamples,
                                                 kVoiceFrameSamples);
    auto size = encoder->encode(frame, packet);
    check(size.ok(), "a seed frame encodes");
    out.emplace_back(packet.begin(), packet.begin() + static_cast<long>(*size));
  }
  return out;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  const auto packets = opusPackets(12);
  VoicePacket voice;
  voice.header = {0x00010002u, 77};
  voice.frame = {5, 48000, 24};
  voice.payload = packets[6];
  std::vector<std::uint8_t> bytes;
  check(writeVoice(voice, bytes).ok(), "a seed voice datagram writes");
  seeds.push_back({"voice.bin", bytes});
  VoiceForwardPacket forward;
  forward.counter = 9;
  forward.speaker_id = 0x00010002u;
  forward.frame = voice.frame;
  forward.payload = packets[7];
  bytes.clear();
  check(writeVoiceForward(forward, bytes).ok(), "a seed forward writes");
  seeds.push_back({"voice_forward.bin", bytes});
  // A frame stream: records of (u16 sequence, u8 capture step in frames, u8 size, payload),
  // one frame missing (FEC), one duplicated.
  std::vector<std::uint8_t> stream;
  for (int i = 0; i < 12; ++i) {
    if (i == 4) continue;
    const int repeat = i == 8 ? 2 : 1;
    for (int r = 0; r < repeat; ++r) {
      stream.push_back(static_cast<std::uint8_t>(i));
      stream.push_back(0);
      stream.push_back(1);
      stream.push_back(static_cast<std::uint8_t>(packets[static_cast<std::size_t>(i)].size()));
      stream.insert(stream.end(), packets[static_cast<std::size_t>(i)].begin(),
                    packets[static_cast<std::size_t>(i)].end());
    }
  }
  seeds.push_back({"frame_stream.bin", stream});
  return seeds;
}

void checkDatagram(std::span<const std::uint8_t> data) {
  VoicePacket voice;
  const Status as_voice = readVoice(data, voice);
  if (as_voice) {
    check(!voice.payload.empty() && voice.payload.size() <= kMaxVoicePayloadBytes,
          "a voice payload is 1..400 bytes");
    check(voice.frame.level <= kVoiceLevelSilent, "a level is 0..127");
    check(peekPacketType(data) == PacketType::kVoice, "peek agrees: voice");
    check(peekMemberId(data) == voice.header.member_id, "peek agrees: member id");
    std::vector<std::uint8_t> again;
    check(writeVoice(voice, again).ok() && std::ranges::equal(again, data),
          "an accepted voice datagram writes back to itself");
  } else {
    check(as_voice.error().message.starts_with("voice datagram"), "a refusal says why");
  }
  VoiceForwardPacket forward;
  const Status as_forward = readVoiceForward(data, forward);
  if (as_forward) {
    check(!forward.payload.empty() && forward.payload.size() <= kMaxVoicePayloadBytes,
          "a forwarded payload is 1..400 bytes");
    check(peekPacketType(data) == PacketType::kVoiceForward, "peek agrees: forward");
    std::vector<std::uint8_t> again;
    check(writeVoiceForward(forward, again).ok() && std::ranges::equal(again, data),
          "an accepted forward writes back to itself");
  } else {
    check(as_forward.error().message.starts_with("voice forward datagram"), "a refusal says why");
  }
  check(!(as_voice && as_forward), "one datagram is never both");
}

// A pulled frame is finite (libopus's float output may pass +-1 on hostile packets), and
// once mixed it never passes the limiter's ceiling.
void checkFrames(std::span<const float> frame, VoiceMixer& mixer, SpatialSourceState& state) {
  check(frame.size() == static_cast<std::size_t>(kVoiceFrameSamples), "a frame is 960 samples");
  for (float v : frame) check(std::isfinite(v), "samples are finite");
  std::vector<float> stereo(2 * kVoiceFrameSamples);
  mixer.beginBlock();
  mixer.addSpeaker(HeadPose{}, glm::vec3(1.0f, 0.0f, 0.5f), frame, state);
  mixer.finishBlock(stereo);
  for (float v : stereo) {
    check(std::isfinite(v) && std::abs(v) <= LimiterSettings{}.ceiling + 1e-4f,
          "the mix never passes the limiter's ceiling");
  }
}

// The input as forwarded frames of one speaker, pushed and pulled on the playout grid.
void checkStream(std::span<const std::uint8_t> data) {
  auto playout = SpeakerPlayout::create();
  check(playout.ok(), "a playout is made");
  VoiceMixer mixer;
  SpatialSourceState state;
  std::vector<float> out(kVoiceFrameSamples);
  std::int64_t now = 0;
  std::uint32_t capture = 0;
  std::size_t at = 0;
  int pulls = 0;
  while (at + 4 <= data.size() && pulls < 400) {
    const auto sequence = static_cast<std::uint16_t>(data[at] | data[at + 1] << 8);
    capture += static_cast<std::uint32_t>(data[at + 2]) * kVoiceFrameSamples;
    const std::size_t size = std::min<std::size_t>(data[at + 3], data.size() - at - 4);
    const auto payload = data.subspan(at + 4, size);
    at += 4 + size;
    const bool accepted = playout->push({sequence, capture, payload}, now);
    check(accepted == (!payload.empty() && payload.size() <= kMaxVoicePayloadBytes),
          "push refuses exactly the empty and oversized payloads");
    // One pull per frame pushed (and a few more at the end).
    const PlayoutDecision d = playout->pull(now, out);
    checkFrames(out, mixer, state);
    if (d.kind == PlayoutKind::kDecode || d.kind == PlayoutKind::kFec) {
      check(!d.packet.empty(), "a decode decision names its packet");
    }
    now += kVoiceFrameSamples;
    ++pulls;
  }
  for (int i = 0; i < 8; ++i, now += kVoiceFrameSamples) {
    playout->pull(now, out);
    checkFrames(out, mixer, state);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  checkDatagram(bytes);
  checkStream(bytes);
  return 0;
}
