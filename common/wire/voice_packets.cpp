#include "common/wire/voice_packets.hpp"

#include <cmath>

namespace vistel::wire {
namespace {

template <typename Stream>
bool serializeFields(Stream& s, VoiceFrameFields& f) {
  return serializeU16(s, f.sequence) && serializeU32(s, f.capture_time) && serializeU8(s, f.level);
}

Status checkPayload(std::span<const std::uint8_t> payload, std::uint8_t level,
                    std::string_view what) {
  if (payload.empty()) return fail("{}: empty Opus payload", what);
  if (payload.size() > kMaxVoicePayloadBytes) {
    return fail("{}: Opus payload of {} bytes (at most {})", what, payload.size(),
                kMaxVoicePayloadBytes);
  }
  if (level > kVoiceLevelSilent)
    return fail("{}: level {} above {}", what, level, kVoiceLevelSilent);
  return {};
}

// Version and type of a datagram that is not one of `type`, in words.
Status wrongKind(std::span<const std::uint8_t> datagram, PacketType type, std::string_view what) {
  if (datagram.size() < 2)
    return fail("{}: {} bytes, shorter than a header", what, datagram.size());
  if (datagram[0] != kWireVersion) {
    return fail("{}: version {} (expected {})", what, datagram[0], kWireVersion);
  }
  return fail("{}: type {:#04x} (expected {:#04x})", what, datagram[1],
              static_cast<unsigned>(type));
}

}  // namespace

std::uint8_t voiceLevelField(float level_dbfs) {
  if (!(level_dbfs <= 0.0f)) return level_dbfs > 0.0f ? 0 : kVoiceLevelSilent;  // NaN: silent
  const float minus = std::round(-level_dbfs);
  return minus >= kVoiceLevelSilent ? kVoiceLevelSilent : static_cast<std::uint8_t>(minus);
}

Status readVoice(std::span<const std::uint8_t> datagram, VoicePacket& out) {
  constexpr std::string_view kWhat = "voice datagram";
  if (datagram.size() > kMaxPlainDatagramBytes) {
    return fail("{}: {} bytes (at most {})", kWhat, datagram.size(), kMaxPlainDatagramBytes);
  }
  if (datagram.size() < kVoiceHeaderBytes) {
    if (datagram.size() >= 2 && datagram[0] == kWireVersion &&
        datagram[1] == static_cast<std::uint8_t>(PacketType::kVoice)) {
      return fail("{}: {} bytes, shorter than its {}-byte header", kWhat, datagram.size(),
                  kVoiceHeaderBytes);
    }
    return wrongKind(datagram, PacketType::kVoice, kWhat);
  }
  ReadStream s(datagram.first(kVoiceHeaderBytes));
  VoicePacket p;
  if (!serialize(s, p.header, PacketType::kVoice)) {
    return wrongKind(datagram, PacketType::kVoice, kWhat);
  }
  serializeFields(s, p.frame);  // the header's length was checked
  p.payload = datagram.subspan(kVoiceHeaderBytes);
  if (Status st = checkPayload(p.payload, p.frame.level, kWhat); !st) return st;
  out = p;
  return {};
}

Status readVoiceForward(std::span<const std::uint8_t> datagram, VoiceForwardPacket& out) {
  constexpr std::string_view kWhat = "voice forward datagram";
  if (datagram.size() > kMaxPlainDatagramBytes) {
    return fail("{}: {} bytes (at most {})", kWhat, datagram.size(), kMaxPlainDatagramBytes);
  }
  if (datagram.size() < kVoiceForwardHeaderBytes) {
    if (datagram.size() >= 2 && datagram[0] == kWireVersion &&
        datagram[1] == static_cast<std::uint8_t>(PacketType::kVoiceForward)) {
      return fail("{}: {} bytes, shorter than its {}-byte header", kWhat, datagram.size(),
                  kVoiceForwardHeaderBytes);
    }
    return wrongKind(datagram, PacketType::kVoiceForward, kWhat);
  }
  ReadStream s(datagram.first(kVoiceForwardHeaderBytes));
  VoiceForwardPacket p;
  if (!serializeServerKind(s, PacketType::kVoiceForward, p.counter)) {
    return wrongKind(datagram, PacketType::kVoiceForward, kWhat);
  }
  serializeU32(s, p.speaker_id);
  serializeFields(s, p.frame);
  p.payload = datagram.subspan(kVoiceForwardHeaderBytes);
  if (Status st = checkPayload(p.payload, p.frame.level, kWhat); !st) return st;
  out = p;
  return {};
}

Status writeVoice(const VoicePacket& packet, std::vector<std::uint8_t>& out) {
  if (Status st = checkPayload(packet.payload, packet.frame.level, "voice datagram"); !st)
    return st;
  VoicePacket p = packet;
  WriteStream s(out);
  serialize(s, p.header, PacketType::kVoice);
  serializeFields(s, p.frame);
  s.align();
  out.insert(out.end(), p.payload.begin(), p.payload.end());
  return {};
}

Status writeVoiceForward(const VoiceForwardPacket& packet, std::vector<std::uint8_t>& out) {
  if (Status st = checkPayload(packet.payload, packet.frame.level, "voice forward datagram"); !st)
    return st;
  VoiceForwardPacket p = packet;
  WriteStream s(out);
  serializeServerKind(s, PacketType::kVoiceForward, p.counter);
  serializeU32(s, p.speaker_id);
  serializeFields(s, p.frame);
  s.align();
  out.insert(out.end(), p.payload.begin(), p.payload.end());
  return {};
}

}  // namespace vistel::wire
