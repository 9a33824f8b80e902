#include "common/wire/packets.hpp"

#include <cassert>
#include <cmath>

namespace vistel::wire {
namespace {

constexpr std::size_t kSnapshotCountOffset = 22;  // entry_count

template <typename Packet>
void writeAny(const Packet& p, std::vector<std::uint8_t>& out) {
  Packet copy = p;
  WriteStream s(out);
  serialize(s, copy);
  s.align();
}

template <typename Packet>
bool readAny(std::span<const std::uint8_t> datagram, Packet& out) {
  if (datagram.size() > kMaxPlainDatagramBytes) return false;
  ReadStream s(datagram);
  return serialize(s, out) && s.atEnd();
}

template <typename Packet>
std::size_t measureAny(const Packet& p) {
  Packet copy = p;
  MeasureStream s;
  serialize(s, copy);
  return s.byteCount();
}

bool finite(double v) { return std::isfinite(v); }

}  // namespace

std::optional<PacketType> peekPacketType(std::span<const std::uint8_t> datagram) {
  if (datagram.size() < 2 || datagram.size() > kMaxDatagramBytes) return std::nullopt;
  if (datagram[0] != kWireVersion) return std::nullopt;
  switch (static_cast<PacketType>(datagram[1])) {
    case PacketType::kHello:
    case PacketType::kPosture:
    case PacketType::kPing:
    case PacketType::kHelloAck:
    case PacketType::kSnapshot:
    case PacketType::kPong:
    case PacketType::kVoice:
    case PacketType::kVoiceForward:
      return static_cast<PacketType>(datagram[1]);
  }
  return std::nullopt;
}

std::size_t clearHeaderBytes(PacketType type) {
  return (static_cast<std::uint8_t>(type) & 0x80) != 0 ? kServerHeaderBytes : kClientHeaderBytes;
}

std::optional<std::uint32_t> peekMemberId(std::span<const std::uint8_t> datagram) {
  if (datagram.size() < kClientHeaderBytes) return std::nullopt;
  ReadStream s(datagram.subspan(2, 4));
  std::uint32_t id = 0;
  if (!serializeU32(s, id)) return std::nullopt;
  return id;
}

void write(const HelloPacket& p, std::vector<std::uint8_t>& out) { writeAny(p, out); }
void write(const PosturePacket& p, std::vector<std::uint8_t>& out) { writeAny(p, out); }
void write(const PingPacket& p, std::vector<std::uint8_t>& out) { writeAny(p, out); }
void write(const HelloAckPacket& p, std::vector<std::uint8_t>& out) { writeAny(p, out); }
void write(const PongPacket& p, std::vector<std::uint8_t>& out) { writeAny(p, out); }

bool readPostureDatagram(std::span<const std::uint8_t> datagram, ClientHeader& header,
                         std::span<const std::uint8_t>& record) {
  if (datagram.size() <= kClientHeaderBytes || datagram.size() > kMaxPlainDatagramBytes) {
    return false;
  }
  ReadStream s(datagram.first(kClientHeaderBytes));
  if (!serialize(s, header, PacketType::kPosture)) return false;
  record = datagram.subspan(kClientHeaderBytes);
  return true;
}

void writePostureDatagram(const ClientHeader& header, std::span<const std::uint8_t> record,
                          std::vector<std::uint8_t>& out) {
  ClientHeader h = header;
  WriteStream w(out);
  serialize(w, h, PacketType::kPosture);
  w.align();
  out.insert(out.end(), record.begin(), record.end());
}

bool read(std::span<const std::uint8_t> datagram, HelloPacket& out) {
  return readAny(datagram, out);
}
bool read(std::span<const std::uint8_t> datagram, PosturePacket& out) {
  return readAny(datagram, out);
}
bool read(std::span<const std::uint8_t> datagram, PingPacket& out) {
  return readAny(datagram, out) && finite(out.client_time);
}
bool read(std::span<const std::uint8_t> datagram, HelloAckPacket& out) {
  return readAny(datagram, out);
}
bool read(std::span<const std::uint8_t> datagram, PongPacket& out) {
  return readAny(datagram, out) && finite(out.server_time);
}

std::size_t measure(const HelloPacket& p) { return measureAny(p); }
std::size_t measure(const PosturePacket& p) { return measureAny(p); }
std::size_t measure(const PingPacket& p) { return measureAny(p); }
std::size_t measure(const HelloAckPacket& p) { return measureAny(p); }
std::size_t measure(const PongPacket& p) { return measureAny(p); }
std::size_t measure(const SnapshotEntry& e) { return measureAny(e); }
std::size_t measure(const Snapshot& s) { return measureAny(s); }
void write(const Snapshot& s, std::vector<std::uint8_t>& out) { writeAny(s, out); }

void writeRecord(const PostureRecord& record, std::vector<std::uint8_t>& out) {
  writeAny(record, out);
}

void beginSnapshot(const SnapshotHeader& header, std::vector<std::uint8_t>& out) {
  assert(out.empty());
  writeAny(header, out);
}

void appendSnapshotEntry(std::uint32_t member_id, std::span<const std::uint8_t> record_bytes,
                         std::vector<std::uint8_t>& out) {
  // The member id through the stream, then the record's bytes as serialized earlier
  // (byte-aligned, so the result equals serializing a SnapshotEntry).
  WriteStream s(out);
  serializeU32(s, member_id);
  out.insert(out.end(), record_bytes.begin(), record_bytes.end());
}

void appendSnapshotWorld(std::span<const std::uint8_t> world_bytes,
                         std::vector<std::uint8_t>& out) {
  assert(out.size() >= kSnapshotHeaderBytes);
  out.insert(out.end(), world_bytes.begin(), world_bytes.end());
}

void finishSnapshot(std::uint8_t entry_count, std::vector<std::uint8_t>& out) {
  assert(out.size() >= kSnapshotHeaderBytes);
  out[kSnapshotCountOffset] = entry_count;
}

void writeSnapshotWorld(std::span<const PropStateRecord> props, const InteractionSection* section,
                        std::vector<std::uint8_t>& out) {
  WriteStream s(out);
  for (PropStateRecord p : props) serialize(s, p);
  // The section's serialize takes a mutable reference only to share the read path; writing
  // does not modify it.
  if (section != nullptr) serialize(s, const_cast<InteractionSection&>(*section));
  s.align();
}

bool readSnapshot(std::span<const std::uint8_t> datagram, Snapshot& out) {
  if (datagram.size() > kMaxPlainDatagramBytes) return false;
  ReadStream s(datagram);
  return serialize(s, out) && finite(out.header.server_time) && s.atEnd();
}

}  // namespace vistel::wire
