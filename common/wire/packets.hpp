// The UDP datagrams of a session (proto/WIRE.md §3), each with one serialize function
// used to read, write and measure it.
//
// These are the *plain* layouts: on the wire every datagram is sealed (datagram_crypto.hpp,
// WIRE.md §3.9): its clear header stays as written here, the rest is encrypted and a
// 16-byte tag follows. Client -> server datagrams start with the 14-byte clear header
// (version, type, member id, counter); server -> client datagrams with a 10-byte one
// (version, type, counter). Writers leave the counter 0 (sealing fills it); readers read
// it (opening checked it). Readers accept a datagram only when it has the
// current version, the expected type, every field in range, and no bytes left over;
// anything else is rejected (false) without side effects on the caller's state beyond the
// output struct.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/wire/bit_stream.hpp"
#include "common/wire/posture_codec.hpp"
#include "common/wire/world_state.hpp"

namespace vistel::wire {

// Version 2 added the collision world to snapshots (props, interaction lists); version 3
// delta-codes the posture a client sends (posture_delta.hpp) and acknowledges it in every
// snapshot's header; version 4 seals every datagram (a counter in the clear header, the
// body encrypted, a 16-byte tag; the UDP key is gone).
inline constexpr std::uint8_t kWireVersion = 4;
// Largest UDP payload either side sends, sealed (stays below common path MTUs). Readers
// reject anything larger.
inline constexpr std::size_t kMaxDatagramBytes = 1200;
// Sealing appends this many bytes (the AEAD tag) to the plain layout.
inline constexpr std::size_t kSealOverheadBytes = 16;
// Largest plain layout: what fits kMaxDatagramBytes once sealed.
inline constexpr std::size_t kMaxPlainDatagramBytes = kMaxDatagramBytes - kSealOverheadBytes;
inline constexpr std::size_t kClientHeaderBytes = 14;  // version, type, member id, counter
inline constexpr std::size_t kServerHeaderBytes = 10;  // version, type, counter
inline constexpr std::size_t kSnapshotHeaderBytes = 29;
inline constexpr std::size_t kSnapshotEntryOverhead = 4;  // member id before each record
inline constexpr int kMaxInteractionParts = 32;           // datagrams of one tick's list

enum class PacketType : std::uint8_t {
  kHello = 0x01,         // client -> server: bind this endpoint to (member id, key)
  kPosture = 0x02,       // client -> server: the sender's newest posture
  kPing = 0x03,          // client -> server: clock-offset probe
  kVoice = 0x04,         // client -> server: one 20 ms Opus voice frame (voice_packets.hpp)
  kHelloAck = 0x81,      // server -> client: endpoint bound
  kSnapshot = 0x82,      // server -> client: other members' newest postures, props, interactions
  kPong = 0x83,          // server -> client: answer to a ping with the server's clock
  kVoiceForward = 0x84,  // server -> client: a voice frame of another member, as it sent it
};

struct ClientHeader {
  std::uint32_t member_id = 0;
  std::uint64_t counter = 0;  // the sender's datagram counter (set by sealing)
};

struct HelloPacket {
  ClientHeader header;
  std::uint32_t attempt = 0;  // the client's hello counter, echoed in the ack
  std::uint64_t cookie = 0;   // 0, or the challenge the server sent to this address
};

// A Posture datagram whose record is a keyframe: the flags byte kPostureKeyframeFlags, then
// the §3.3 record (what a sender's first posture, and every key_interval_s, is). Other
// Posture datagrams carry a delta record (readPostureDatagram, PostureDeltaDecoder).
inline constexpr std::uint8_t kPostureKeyframeFlags = 0x01;
struct PosturePacket {
  ClientHeader header;
  PostureRecord record;
};

struct PingPacket {
  ClientHeader header;
  std::uint32_t ping_id = 0;
  double client_time = 0.0;  // sender's clock, seconds (echoed)
};

// cookie != 0: a challenge (the address is not bound yet: send the hello again with this
// cookie); 0: the address is bound.
struct HelloAckPacket {
  std::uint32_t member_id = 0;
  std::uint32_t attempt = 0;
  std::uint64_t cookie = 0;
  std::uint64_t counter = 0;  // the sender's datagram counter (set by sealing)
};

// The client pairs it with its ping by id (it remembers when it sent each).
struct PongPacket {
  std::uint32_t ping_id = 0;
  double server_time = 0.0;   // server clock when the ping was handled, seconds
  std::uint64_t counter = 0;  // the sender's datagram counter (set by sealing)
};

struct SnapshotHeader {
  std::uint32_t tick = 0;        // room tick counter
  double server_time = 0.0;      // server clock at the tick, seconds
  std::uint8_t entry_count = 0;  // posture entries
  std::uint8_t prop_count = 0;   // prop states
  std::uint8_t part = 0;         // which part of the tick's interaction list this carries
  std::uint8_t part_count = 0;   // parts of the tick's list (1..32); 0 = no section here
  // The recipient's own posture stream (version 3): the newest sequence the server decoded
  // (when kAckValid) and whether it needs a keyframe (kAckWantKeyframe).
  std::uint16_t posture_ack = 0;
  std::uint8_t ack_flags = 0;
  std::uint64_t counter = 0;  // the sender's datagram counter (set by sealing; bytes 2..9)
};
inline constexpr std::uint8_t kAckValid = 1;
inline constexpr std::uint8_t kAckWantKeyframe = 2;

struct SnapshotEntry {
  std::uint32_t member_id = 0;
  PostureRecord record;
};

// A whole snapshot datagram as read (vectors are resized; reuse the struct to avoid
// allocating per packet).
struct Snapshot {
  SnapshotHeader header;
  std::vector<SnapshotEntry> entries;  // (entry_count)
  std::vector<PropStateRecord> props;  // (prop_count)
  InteractionSection interactions;     // meaningful when header.part_count > 0
};

// ----- serialize functions (read, write, measure) -----

template <typename Stream>
bool serializeKind(Stream& s, PacketType type) {
  std::uint8_t version = kWireVersion;
  auto kind = static_cast<std::uint8_t>(type);
  if (!serializeU8(s, version) || !serializeU8(s, kind)) return false;
  return version == kWireVersion && kind == static_cast<std::uint8_t>(type);
}

// A server -> client clear header: version, type, counter.
template <typename Stream>
bool serializeServerKind(Stream& s, PacketType type, std::uint64_t& counter) {
  return serializeKind(s, type) && serializeU64(s, counter);
}

template <typename Stream>
bool serialize(Stream& s, ClientHeader& h, PacketType type) {
  return serializeKind(s, type) && serializeU32(s, h.member_id) && serializeU64(s, h.counter);
}

template <typename Stream>
bool serialize(Stream& s, HelloPacket& p) {
  return serialize(s, p.header, PacketType::kHello) && serializeU32(s, p.attempt) &&
         serializeU64(s, p.cookie);
}

template <typename Stream>
bool serialize(Stream& s, PosturePacket& p) {
  std::uint8_t flags = kPostureKeyframeFlags;
  return serialize(s, p.header, PacketType::kPosture) && serializeU8(s, flags) &&
         flags == kPostureKeyframeFlags && serialize(s, p.record);
}

template <typename Stream>
bool serialize(Stream& s, PingPacket& p) {
  return serialize(s, p.header, PacketType::kPing) && serializeU32(s, p.ping_id) &&
         serializeF64(s, p.client_time);
}

template <typename Stream>
bool serialize(Stream& s, HelloAckPacket& p) {
  return serializeServerKind(s, PacketType::kHelloAck, p.counter) && serializeU32(s, p.member_id) &&
         serializeU32(s, p.attempt) && serializeU64(s, p.cookie);
}

template <typename Stream>
bool serialize(Stream& s, PongPacket& p) {
  return serializeServerKind(s, PacketType::kPong, p.counter) && serializeU32(s, p.ping_id) &&
         serializeF64(s, p.server_time);
}

template <typename Stream>
bool serialize(Stream& s, SnapshotHeader& h) {
  if (!serializeServerKind(s, PacketType::kSnapshot, h.counter) || !serializeU32(s, h.tick) ||
      !serializeF64(s, h.server_time) || !serializeU8(s, h.entry_count) ||
      !serializeU8(s, h.prop_count) || !serializeU8(s, h.part) || !serializeU8(s, h.part_count) ||
      !serializeU16(s, h.posture_ack) || !serializeU8(s, h.ack_flags)) {
    return false;
  }
  if ((h.ack_flags & ~(kAckValid | kAckWantKeyframe)) != 0) return false;
  // A section is part `part` of `part_count`; without one, part is 0.
  return h.part_count <= kMaxInteractionParts &&
         (h.part_count == 0 ? h.part == 0 : h.part < h.part_count);
}

template <typename Stream>
bool serialize(Stream& s, SnapshotEntry& e) {
  return serializeU32(s, e.member_id) && serialize(s, e.record);
}

// The whole datagram: header, entries, prop states, then the interaction section when
// part_count > 0. Reading checks each count against the bytes left before sizing.
template <typename Stream>
bool serialize(Stream& s, Snapshot& x) {
  if constexpr (!Stream::kReading) {
    x.header.entry_count = static_cast<std::uint8_t>(x.entries.size());
    x.header.prop_count = static_cast<std::uint8_t>(x.props.size());
  }
  if (!serialize(s, x.header)) return false;
  if constexpr (Stream::kReading) {
    const std::size_t min_entry = kSnapshotEntryOverhead + kPostureHeaderBytes;
    if (x.header.entry_count > s.bitsLeft() / 8 / min_entry) return false;
    x.entries.resize(x.header.entry_count);
  }
  for (SnapshotEntry& e : x.entries) {
    if (!serialize(s, e)) return false;
  }
  if constexpr (Stream::kReading) {
    if (x.header.prop_count > s.bitsLeft() / 8 / kPropStateBytes) return false;
    x.props.resize(x.header.prop_count);
  }
  for (PropStateRecord& p : x.props) {
    if (!serialize(s, p)) return false;
  }
  if (x.header.part_count == 0) {
    if constexpr (Stream::kReading) x.interactions.clear();
    return true;
  }
  return serialize(s, x.interactions);
}

// ----- whole datagrams -----

// The packet type of a datagram with the current version, or nullopt (wrong version,
// unknown type, too short or too long). Cheap: for routing before a full read. Works on
// sealed and plain datagrams alike (the first two bytes are clear).
std::optional<PacketType> peekPacketType(std::span<const std::uint8_t> datagram);
// The member id of a client -> server datagram (bytes 2..5), or nullopt when shorter
// than the client header.
std::optional<std::uint32_t> peekMemberId(std::span<const std::uint8_t> datagram);
// The clear header's size for a packet type: kClientHeaderBytes for client -> server
// types, kServerHeaderBytes for server -> client ones (what sealing leaves in clear).
std::size_t clearHeaderBytes(PacketType type);

// Appends the datagram's bytes to out.
void write(const HelloPacket& p, std::vector<std::uint8_t>& out);
void write(const PosturePacket& p, std::vector<std::uint8_t>& out);
void write(const PingPacket& p, std::vector<std::uint8_t>& out);
void write(const HelloAckPacket& p, std::vector<std::uint8_t>& out);
void write(const PongPacket& p, std::vector<std::uint8_t>& out);

// A Posture datagram's client header and its record's bytes (a keyframe or a delta, for a
// PostureDeltaDecoder): false when it is not a version 3 Posture datagram with a header
// and at least one record byte. `record` points into `datagram`.
bool readPostureDatagram(std::span<const std::uint8_t> datagram, ClientHeader& header,
                         std::span<const std::uint8_t>& record);
// Appends a Posture datagram: the client header, then the record bytes as given.
void writePostureDatagram(const ClientHeader& header, std::span<const std::uint8_t> record,
                          std::vector<std::uint8_t>& out);

// Reads a whole datagram: true only when it is exactly one valid message of that type
// (for a Posture datagram: a keyframe).
bool read(std::span<const std::uint8_t> datagram, HelloPacket& out);
bool read(std::span<const std::uint8_t> datagram, PosturePacket& out);
bool read(std::span<const std::uint8_t> datagram, PingPacket& out);
bool read(std::span<const std::uint8_t> datagram, HelloAckPacket& out);
bool read(std::span<const std::uint8_t> datagram, PongPacket& out);

// Serialized size in bytes.
std::size_t measure(const HelloPacket& p);
std::size_t measure(const PosturePacket& p);
std::size_t measure(const PingPacket& p);
std::size_t measure(const HelloAckPacket& p);
std::size_t measure(const PongPacket& p);
std::size_t measure(const SnapshotEntry& e);
std::size_t measure(const Snapshot& s);

// Writes a whole snapshot datagram (counts taken from the vectors).
void write(const Snapshot& s, std::vector<std::uint8_t>& out);

// Serialized bytes of a posture record alone (what a server keeps per member and copies
// into snapshots).
void writeRecord(const PostureRecord& record, std::vector<std::uint8_t>& out);

// Snapshots are built incrementally, so that a server copies bytes it serialized once:
// a header (its prop_count, part and part_count final; entry_count patched at the end),
// entries of a member id and a record's bytes, then the world bytes (the prop states and
// the interaction section, from writeSnapshotWorld, matching the header's counts), then
// the entry count. `out` must be empty at begin. The result equals write(Snapshot).
void beginSnapshot(const SnapshotHeader& header, std::vector<std::uint8_t>& out);
void appendSnapshotEntry(std::uint32_t member_id, std::span<const std::uint8_t> record_bytes,
                         std::vector<std::uint8_t>& out);
void appendSnapshotWorld(std::span<const std::uint8_t> world_bytes, std::vector<std::uint8_t>& out);
void finishSnapshot(std::uint8_t entry_count, std::vector<std::uint8_t>& out);

// The world part of a snapshot: the prop states, then the section if not null (appended
// to out; allocation-free once out has the capacity).
void writeSnapshotWorld(std::span<const PropStateRecord> props, const InteractionSection* section,
                        std::vector<std::uint8_t>& out);

// Reads a whole snapshot datagram. All or nothing: false if any part is malformed or
// bytes are left over.
bool readSnapshot(std::span<const std::uint8_t> datagram, Snapshot& out);

}  // namespace vistel::wire
