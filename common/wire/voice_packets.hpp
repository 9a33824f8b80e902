// The voice datagrams of a session (proto/WIRE.md §3.10, proto/VOICE.md): Voice (0x04), one
// 20 ms Opus frame a member sends, and VoiceForward (0x84), that frame as the server passes
// it on to a listener. Plain layouts, sealed on the wire like every datagram
// (datagram_crypto.hpp): the clear header stays, the rest is encrypted, a 16-byte tag
// follows.
//
//   Voice:        client header (14 bytes: version, type, member id, counter),
//                 u16 sequence, u32 capture time, u8 level, Opus payload (1..400 bytes)
//   VoiceForward: server header (10 bytes: version, type, counter), u32 speaker id,
//                 u16 sequence, u32 capture time, u8 level, Opus payload (1..400 bytes)
//
// The payload is the rest of the datagram. Sequence: +1 per voice datagram the speaker
// sends (wraps). Capture time: the frame's first sample in samples at 48 kHz of the
// sender's clock (wraps every 24.8 h; vistel's client counts on its estimate of the server
// clock, so a listener can tell mouth-to-ear latency). Level: the frame's RMS before
// coding in -dBFS, 0..127, 127 = silence (as RFC 6464). The server forwards sequence, time,
// level and payload unchanged.
//
// Readers reject, with an Error that says why: a datagram longer than
// kMaxPlainDatagramBytes, another version or type, a header cut short, a level above 127,
// an empty payload or one longer than kMaxVoicePayloadBytes. They never decode the Opus
// payload (the receiver's decoder checks it). The views point into the datagram read.
// Writers append to `out` (nothing allocated beyond its growth) and refuse a payload out
// of range.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/base/result.hpp"
#include "common/wire/packets.hpp"

namespace vistel::wire {

inline constexpr std::size_t kVoiceFieldBytes = 7;         // sequence, capture time, level
inline constexpr std::size_t kMaxVoicePayloadBytes = 400;  // one Opus frame (~60 at 24 kbit/s)
inline constexpr std::uint8_t kVoiceLevelSilent = 127;     // -dBFS: silence or quieter
inline constexpr std::size_t kVoiceHeaderBytes = kClientHeaderBytes + kVoiceFieldBytes;  // 21
inline constexpr std::size_t kVoiceForwardHeaderBytes = kServerHeaderBytes + 4 + kVoiceFieldBytes;
// Largest plain voice datagrams: 421 and 421 bytes (437 sealed).
inline constexpr std::size_t kMaxVoiceDatagramBytes = kVoiceHeaderBytes + kMaxVoicePayloadBytes;
inline constexpr std::size_t kMaxVoiceForwardBytes =
    kVoiceForwardHeaderBytes + kMaxVoicePayloadBytes;

// What both datagrams carry about the frame.
struct VoiceFrameFields {
  std::uint16_t sequence = 0;
  std::uint32_t capture_time = 0;          // samples at 48 kHz, sender clock
  std::uint8_t level = kVoiceLevelSilent;  // -dBFS, 0..127
};

struct VoicePacket {
  ClientHeader header;
  VoiceFrameFields frame;
  std::span<const std::uint8_t> payload;  // one Opus packet, 1..kMaxVoicePayloadBytes
};

struct VoiceForwardPacket {
  std::uint64_t counter = 0;  // set by sealing
  std::uint32_t speaker_id = 0;
  VoiceFrameFields frame;
  std::span<const std::uint8_t> payload;
};

// The level field of a frame whose RMS is level_dbfs (dB full scale): -level clamped to
// 0..127 (NaN: silent).
std::uint8_t voiceLevelField(float level_dbfs);

Status readVoice(std::span<const std::uint8_t> datagram, VoicePacket& out);
Status readVoiceForward(std::span<const std::uint8_t> datagram, VoiceForwardPacket& out);
// Errors: a payload empty or longer than kMaxVoicePayloadBytes, a level above 127 (nothing
// is appended then).
Status writeVoice(const VoicePacket& packet, std::vector<std::uint8_t>& out);
Status writeVoiceForward(const VoiceForwardPacket& packet, std::vector<std::uint8_t>& out);

}  // namespace vistel::wire
