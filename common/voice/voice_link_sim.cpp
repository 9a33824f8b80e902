// The voice path in simulated time: the sender runs first (its packets do not depend on
// the receiver), then the receiver consumes them in arrival order on its own clock.
#include "common/voice/voice_link_sim.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "common/voice/mixer.hpp"
#include "common/voice/speaker_playout.hpp"

namespace vistel {

namespace {

struct SimPacket {
  double arrival = 0.0;  // receiver clock, samples
  uint16_t sequence = 0;
  uint32_t capture_time = 0;
  std::vector<uint8_t> payload;
};

}  // namespace

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<std::ptrdiff_t>(
      std::floor(std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + rank, values.end());
  return values[static_cast<size_t>(rank)];
}

Result<VoiceLinkResult> simulateVoiceLink(std::span<const float> speech,
                                          const VoiceLinkSettings& settings) {
  auto encoder = OpusVoiceEncoder::create(settings.codec);
  if (!encoder) return encoder.error();
  auto vad = VoiceActivity::create(settings.vad);
  if (!vad) return vad.error();
  auto playout = SpeakerPlayout::create(settings.buffer);
  if (!playout) return playout.error();

  VoiceLinkResult result;
  result.codec_delay_samples = encoder->lookaheadSamples();
  const double clock_scale = 1.0 / (1.0 + settings.sender_clock_ppm * 1e-6);  // sender->receiver
  std::mt19937 rng(settings.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  // Sender: frame k is captured over [k, k + 1) frames of its clock and sent at its end.
  const size_t frames = speech.size() / kVoiceFrameSamples;
  std::vector<SimPacket> packets;
  packets.reserve(frames);
  std::vector<float> frame(kVoiceFrameSamples);
  std::vector<uint8_t> bytes(kVoiceMaxPacketBytes);
  uint16_t sequence = 0;
  for (size_t k = 0; k < frames; ++k) {
    std::copy_n(speech.begin() + static_cast<std::ptrdiff_t>(k * kVoiceFrameSamples),
                kVoiceFrameSamples, frame.begin());
    if (settings.use_vad && !vad->process(frame).send) continue;
    auto size = encoder->encode(frame, bytes);
    if (!size) return size.error();
    ++result.packets_sent;
    result.bytes_sent += static_cast<int64_t>(*size);
    const uint32_t capture = static_cast<uint32_t>(k * kVoiceFrameSamples);
    const uint16_t this_sequence = sequence++;
    const double lost = unit(rng);
    const double jitter = unit(rng) * settings.jitter_s;
    if (lost < settings.loss) continue;
    SimPacket packet;
    packet.arrival = static_cast<double>((k + 1) * kVoiceFrameSamples) * clock_scale +
                     (settings.base_delay_s + jitter) * kVoiceSampleRate;
    packet.sequence = this_sequence;
    packet.capture_time = capture;
    packet.payload.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(*size));
    packets.push_back(std::move(packet));
  }
  std::stable_sort(packets.begin(), packets.end(),
                   [](const SimPacket& a, const SimPacket& b) { return a.arrival < b.arrival; });

  // Receiver: a pull every 20 ms of its clock, after pushing what has arrived.
  result.heard.assign(speech.size(), 0.0f);
  VoiceMixer mixer;
  SpatialSourceState spatial_state;
  HeadPose listener;
  const glm::vec3 p_speaker(1.0f, 0.0f, 1.7f);  // 2 m away, ahead and to the left
  std::vector<float> mono(kVoiceFrameSamples), stereo(2 * kVoiceFrameSamples);
  const double end_time = static_cast<double>(speech.size()) * clock_scale +
                          (settings.base_delay_s + settings.jitter_s + 1.0) * kVoiceSampleRate;
  size_t next_packet = 0;
  for (int64_t now = settings.pull_phase_samples; static_cast<double>(now) < end_time;
       now += kVoiceFrameSamples) {
    for (; next_packet < packets.size() && packets[next_packet].arrival <= static_cast<double>(now);
         ++next_packet) {
      const SimPacket& p = packets[next_packet];
      playout->push({p.sequence, p.capture_time, p.payload},
                    static_cast<int64_t>(std::floor(p.arrival)));
    }
    const PlayoutDecision decision = playout->pull(now, mono);
    // Mouth to ear for frames from a packet; the heard timeline for everything played.
    if (decision.kind == PlayoutKind::kDecode || decision.kind == PlayoutKind::kFec) {
      const double captured = static_cast<double>(decision.capture_time) * clock_scale;
      result.latency_s.push_back(
          (static_cast<double>(now + settings.output_buffer_samples) - captured) /
          kVoiceSampleRate);
    }
    if (decision.capture_time >= 0 &&
        decision.capture_time + kVoiceFrameSamples <= static_cast<int64_t>(speech.size())) {
      std::copy(mono.begin(), mono.end(),
                result.heard.begin() + static_cast<std::ptrdiff_t>(decision.capture_time));
    }
    if (settings.spatialise) {
      mixer.beginBlock();
      mixer.addSpeaker(listener, p_speaker, mono, spatial_state);
      mixer.finishBlock(stereo);
      result.stereo.insert(result.stereo.end(), stereo.begin(), stereo.end());
    }
  }
  result.stats = playout->buffer().stats();
  return result;
}

}  // namespace vistel
