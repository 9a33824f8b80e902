#include "common/wire/packets.hpp"

#include <cassert>
#include <cmath>

namespace vistel::wire {
namespace {

constexpr std::size_t kSnapshotCountOffset = 14;

template <typename Packet>
void writeAny(const Packet& p, std::vector<std::uint8_t>& out) {
  Packet copy = p;
  WriteStream s(out);
  serialize(s, copy);
  s.align();
}

template <typename Packet>
bool readAny(std::span<const std::uint8_t> datagram, Packet& out) {
  if (datagram.size() > kMaxDatagramBytes) return false;
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
      return static_cast<PacketType>(datagram[1]);
  }
  return std::nullopt;
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
  return readAny(datagram, out) && finite(out.client_time) && finite(out.server_time);
}

std::size_t measure(const HelloPacket& p) { return measureAny(p); }
std::size_t measure(const PosturePacket& p) { return measureAny(p); }
std::size_t measure(const PingPacket& p) { return measureAny(p); }
std::size_t measure(const HelloAckPacket& p) { return measureAny(p); }
std::size_t measure(const PongPacket& p) { return measureAny(p); }
std::size_t measure(const SnapshotEntry& e) { return measureAny(e); }

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

void finishSnapshot(std::uint8_t entry_count, std::vector<std::uint8_t>& out) {
  assert(out.size() >= kSnapshotHeaderBytes);
  out[kSnapshotCountOffset] = entry_count;
}

bool readSnapshot(std::span<const std::uint8_t> datagram, SnapshotHeader& header,
                  std::vector<SnapshotEntry>& entries) {
  if (datagram.size() > kMaxDatagramBytes) return false;
  ReadStream s(datagram);
  if (!serialize(s, header) || !finite(header.server_time)) return false;
  // Each entry takes at least 4 + 13 bytes: refuse counts the datagram cannot hold
  // before sizing anything.
  const std::size_t min_entry = kSnapshotEntryOverhead + kPostureHeaderBytes;
  if (header.entry_count > s.bitsLeft() / 8 / min_entry) return false;
  entries.resize(header.entry_count);
  for (SnapshotEntry& e : entries) {
    if (!serialize(s, e)) return false;
  }
  return s.atEnd();
}

}  // namespace vistel::wire
