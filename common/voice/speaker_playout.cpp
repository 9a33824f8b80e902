// A speaker's receive side: VoiceJitterBuffer decisions carried out by OpusVoiceDecoder.
#include "common/voice/speaker_playout.hpp"

#include <algorithm>

namespace vistel {

Result<SpeakerPlayout> SpeakerPlayout::create(const JitterBufferSettings& settings) {
  auto decoder = OpusVoiceDecoder::create();
  if (!decoder) return decoder.error();
  return SpeakerPlayout(VoiceJitterBuffer(settings), std::move(*decoder));
}

PlayoutDecision SpeakerPlayout::pull(int64_t now, std::span<float> out) {
  const PlayoutDecision decision = buffer_.pull(now);
  switch (decision.kind) {
    case PlayoutKind::kSilence:
      std::fill_n(out.begin(), kVoiceFrameSamples, 0.0f);
      decoder_active_ = false;
      break;
    case PlayoutKind::kDecode:
      if (!decoder_.decode(decision.packet, out)) {
        ++decode_errors_;
        decoder_.conceal(out);
      }
      decoder_active_ = true;
      break;
    case PlayoutKind::kFec:
      if (!decoder_.recoverFromNext(decision.packet, out)) ++decode_errors_;
      break;
    case PlayoutKind::kConceal:
      // Concealment extrapolates what the decoder played last; with nothing played in
      // this talkspurt there is nothing to extend.
      if (decoder_active_) {
        decoder_.conceal(out);
      } else {
        std::fill_n(out.begin(), kVoiceFrameSamples, 0.0f);
      }
      break;
  }
  return decision;
}

}  // namespace vistel
