// The Opus voice codec over libopus (RFC 6716; FEC and PLC as libopus implements them).
#include "common/voice/opus_voice.hpp"

#include <algorithm>
#include <cassert>

#include <opus.h>

namespace vistel {

void OpusVoiceEncoder::Deleter::operator()(OpusEncoder* encoder) const {
  opus_encoder_destroy(encoder);
}
void OpusVoiceDecoder::Deleter::operator()(OpusDecoder* decoder) const {
  opus_decoder_destroy(decoder);
}

Result<OpusVoiceEncoder> OpusVoiceEncoder::create(const OpusVoiceSettings& settings) {
  if (settings.complexity < 0 || settings.complexity > 10) {
    return fail("opus voice encoder: complexity {} outside 0..10", settings.complexity);
  }
  int err = OPUS_OK;
  OpusVoiceEncoder result;
  result.encoder_.reset(opus_encoder_create(kVoiceSampleRate, 1, OPUS_APPLICATION_AUDIO, &err));
  if (err != OPUS_OK || !result.encoder_) {
    return fail("opus voice encoder: {}", opus_strerror(err));
  }
  OpusEncoder* enc = result.encoder_.get();
  opus_encoder_ctl(enc, OPUS_SET_SIGNAL(OPUS_SIGNAL_VOICE));
  opus_encoder_ctl(enc, OPUS_SET_INBAND_FEC(1));
  opus_encoder_ctl(enc, OPUS_SET_DTX(settings.dtx ? 1 : 0));
  opus_encoder_ctl(enc, OPUS_SET_COMPLEXITY(settings.complexity));
  opus_encoder_ctl(enc, OPUS_SET_VBR(1));
  opus_encoder_ctl(enc, OPUS_SET_VBR_CONSTRAINT(1));
  opus_encoder_ctl(enc, OPUS_SET_MAX_BANDWIDTH(settings.wideband ? OPUS_BANDWIDTH_WIDEBAND
                                                                 : OPUS_BANDWIDTH_FULLBAND));
  result.settings_ = settings;
  if (auto status = result.setBitrate(settings.bitrate_bps); !status) return status.error();
  if (auto status = result.setExpectedLoss(settings.expected_loss_percent); !status) {
    return status.error();
  }
  return result;
}

Status OpusVoiceEncoder::setBitrate(int bitrate_bps) {
  if (bitrate_bps < 16000 || bitrate_bps > 32000) {
    return fail("opus voice encoder: bitrate {} bit/s outside 16000..32000", bitrate_bps);
  }
  if (opus_encoder_ctl(encoder_.get(), OPUS_SET_BITRATE(bitrate_bps)) != OPUS_OK) {
    return fail("opus voice encoder: libopus refused bitrate {}", bitrate_bps);
  }
  settings_.bitrate_bps = bitrate_bps;
  return {};
}

Status OpusVoiceEncoder::setExpectedLoss(int loss_percent) {
  if (loss_percent < 0 || loss_percent > 100) {
    return fail("opus voice encoder: loss {}% outside 0..100", loss_percent);
  }
  opus_encoder_ctl(encoder_.get(), OPUS_SET_PACKET_LOSS_PERC(loss_percent));
  settings_.expected_loss_percent = loss_percent;
  return {};
}

int OpusVoiceEncoder::lookaheadSamples() const {
  opus_int32 lookahead = 0;
  opus_encoder_ctl(encoder_.get(), OPUS_GET_LOOKAHEAD(&lookahead));
  return static_cast<int>(lookahead);
}

Result<size_t> OpusVoiceEncoder::encode(std::span<const float> frame, std::span<uint8_t> out) {
  assert(frame.size() == static_cast<size_t>(kVoiceFrameSamples));
  const int bytes = opus_encode_float(encoder_.get(), frame.data(), kVoiceFrameSamples, out.data(),
                                      static_cast<opus_int32>(out.size()));
  if (bytes < 0) return fail("opus voice encoder: {}", opus_strerror(bytes));
  return static_cast<size_t>(bytes);
}

Result<OpusVoiceDecoder> OpusVoiceDecoder::create() {
  int err = OPUS_OK;
  OpusVoiceDecoder result;
  result.decoder_.reset(opus_decoder_create(kVoiceSampleRate, 1, &err));
  if (err != OPUS_OK || !result.decoder_) {
    return fail("opus voice decoder: {}", opus_strerror(err));
  }
  return result;
}

namespace {

// Checks a packet from the network before libopus decodes it: not empty, parseable and
// exactly one 20 ms frame long.
Status checkPacket(std::span<const uint8_t> packet) {
  if (packet.empty() || packet.size() > 1275) {
    return fail("opus voice packet: {} bytes (1..1275 expected)", packet.size());
  }
  const int samples = opus_packet_get_nb_samples(
      packet.data(), static_cast<opus_int32>(packet.size()), kVoiceSampleRate);
  if (samples < 0) return fail("opus voice packet: {}", opus_strerror(samples));
  if (samples != kVoiceFrameSamples) {
    return fail("opus voice packet: {} samples, expected {} (20 ms)", samples, kVoiceFrameSamples);
  }
  return {};
}

}  // namespace

Status OpusVoiceDecoder::decode(std::span<const uint8_t> packet, std::span<float> out) {
  assert(out.size() >= static_cast<size_t>(kVoiceFrameSamples));
  if (auto status = checkPacket(packet); !status) {
    std::fill_n(out.begin(), kVoiceFrameSamples, 0.0f);
    return status;
  }
  const int got =
      opus_decode_float(decoder_.get(), packet.data(), static_cast<opus_int32>(packet.size()),
                        out.data(), kVoiceFrameSamples, 0);
  if (got != kVoiceFrameSamples) {
    std::fill_n(out.begin(), kVoiceFrameSamples, 0.0f);
    return fail("opus voice packet: {}", got < 0 ? opus_strerror(got) : "short frame");
  }
  return {};
}

void OpusVoiceDecoder::conceal(std::span<float> out) {
  assert(out.size() >= static_cast<size_t>(kVoiceFrameSamples));
  const int got = opus_decode_float(decoder_.get(), nullptr, 0, out.data(), kVoiceFrameSamples, 0);
  if (got != kVoiceFrameSamples) std::fill_n(out.begin(), kVoiceFrameSamples, 0.0f);
}

Status OpusVoiceDecoder::recoverFromNext(std::span<const uint8_t> next_packet,
                                         std::span<float> out) {
  assert(out.size() >= static_cast<size_t>(kVoiceFrameSamples));
  if (auto status = checkPacket(next_packet); !status) {
    conceal(out);
    return status;
  }
  const int got = opus_decode_float(decoder_.get(), next_packet.data(),
                                    static_cast<opus_int32>(next_packet.size()), out.data(),
                                    kVoiceFrameSamples, 1);
  if (got != kVoiceFrameSamples) {
    conceal(out);
    return fail("opus voice packet (fec): {}", got < 0 ? opus_strerror(got) : "short frame");
  }
  return {};
}

}  // namespace vistel
