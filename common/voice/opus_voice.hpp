// The Opus voice codec (libopus): 48 kHz mono, 20 ms frames.
//
// OpusVoiceEncoder encodes one 960-sample float frame into one packet with the voice
// signal hint, in-band FEC on (each packet carries a low-bitrate copy of the previous
// frame), a packet-loss percentage hint (which sizes that FEC), a bitrate of 16..32 kbit/s
// (constrained VBR: a talkspurt's rate stays near it), the coded band limited to 0..8 kHz
// (Opus wideband, where speech is; optional) and optional DTX. The application is
// OPUS_APPLICATION_AUDIO, not VOIP: VOIP's perceptual shaping and variable high-pass keep
// speech intelligible but not its waveform (synthetic speech at 16 kbit/s came back with
// correlation 0.945 for a 120 Hz voice and 0.47 for a 220 Hz one, against 0.992 and 0.993
// with AUDIO), and noise is suppressed before the encoder anyway (VoiceActivity).
// OpusVoiceDecoder decodes a packet into 960 samples, conceals a missing frame (PLC:
// libopus's decode of a null packet), or recovers a missing frame from the FEC data of the
// packet that followed it (decode_fec).
//
// Packets come from the network: decode() checks them and returns an Error for a packet
// libopus rejects or one that is not exactly 20 ms. Each call costs one libopus call
// (tens of microseconds); no allocation after create().
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "common/base/result.hpp"
#include "common/voice/voice_format.hpp"

struct OpusEncoder;
struct OpusDecoder;

namespace vistel {

struct OpusVoiceSettings {
  int bitrate_bps = 16000;         // 16000..32000 (16: ~29 kbit/s of sealed datagrams)
  int expected_loss_percent = 10;  // 0..100, the FEC's sizing hint
  bool dtx = false;                // discontinuous transmission in silence
  int complexity = 9;              // 0..10
  bool wideband = true;            // code 0..8 kHz only (false: up to fullband, 20 kHz)
};

class OpusVoiceEncoder {
 public:
  // Errors: bitrate outside 16..32 kbit/s, loss outside 0..100, libopus failures.
  static Result<OpusVoiceEncoder> create(const OpusVoiceSettings& settings);

  // Encodes exactly kVoiceFrameSamples mono samples into out (>= kVoiceMaxPacketBytes is
  // ample). Returns the packet's size in bytes; with DTX a 1..2 byte packet means silence.
  Result<size_t> encode(std::span<const float> frame, std::span<uint8_t> out);

  Status setBitrate(int bitrate_bps);        // 16000..32000
  Status setExpectedLoss(int loss_percent);  // 0..100
  int lookaheadSamples() const;              // the codec's delay, samples at 48 kHz
  const OpusVoiceSettings& settings() const { return settings_; }

 private:
  OpusVoiceEncoder() = default;  // through create() only

  struct Deleter {
    void operator()(OpusEncoder* encoder) const;
  };
  std::unique_ptr<OpusEncoder, Deleter> encoder_;
  OpusVoiceSettings settings_;
};

class OpusVoiceDecoder {
 public:
  static Result<OpusVoiceDecoder> create();

  // Decodes one packet into out (kVoiceFrameSamples samples). Errors: an empty or
  // malformed packet, or one whose duration is not 20 ms (out is then left as silence).
  Status decode(std::span<const uint8_t> packet, std::span<float> out);

  // Packet-loss concealment for one missing frame (extrapolates, fading to silence).
  void conceal(std::span<float> out);

  // Recovers the frame before next_packet from next_packet's in-band FEC data; where
  // that packet carries none, libopus conceals instead. Errors as decode().
  Status recoverFromNext(std::span<const uint8_t> next_packet, std::span<float> out);

 private:
  OpusVoiceDecoder() = default;  // through create() only

  struct Deleter {
    void operator()(OpusDecoder* decoder) const;
  };
  std::unique_ptr<OpusDecoder, Deleter> decoder_;
};

}  // namespace vistel
