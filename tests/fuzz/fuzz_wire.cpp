// libFuzzer target: the wire decoders (common/wire, proto/WIRE.md) on arbitrary bytes.
// Each input is read two ways:
//   - as one UDP datagram, by every reader: an accepted datagram writes back to exactly
//     the same bytes, measure() agrees, peekPacketType / peekMemberId agree with it, and
//     its posture records decode to finite unit rotations;
//   - as a TCP byte stream cut into pieces (fuzz::feedInChunks): FrameDecoder returns
//     exactly the frames a one-pass reading of the whole stream finds, breaks exactly when
//     that reading meets an oversized length, and keeps the rest buffered.
//   - as a sealed datagram (datagram_crypto.hpp, WIRE.md §3.9) under a fixed test key:
//     opening never reads outside the input, a datagram that opens is one sealed with that
//     key, and every plain datagram a reader accepts seals and opens back to itself (and
//     not with a changed byte).
// Seeds: datagrams of every type (plain and sealed) and framed streams written by the
// codec itself.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/framing.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_codec.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using namespace vistel::wire;
using fuzz::check;

constexpr std::size_t kMaxFrame = 256;  // FrameDecoder's limit in this target

// The key sealed seeds use and inputs are opened with.
AeadKey fuzzKey() {
  AeadKey k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(0xA0 + i);
  return k;
}

// The frames of a TCP stream read in one pass: the reference FrameDecoder must agree with.
struct Framing {
  std::vector<std::vector<std::uint8_t>> frames;
  bool broken = false;
  std::size_t rest = 0;  // bytes after the last frame (when not broken)
};

Framing frameAtOnce(std::span<const std::uint8_t> stream) {
  Framing f;
  std::size_t at = 0;
  while (stream.size() - at >= kFrameHeaderBytes) {
    const std::uint32_t n = fuzz::loadU32(stream.data() + at);
    if (n > kMaxFrame) {
      f.broken = true;
      return f;
    }
    if (stream.size() - at - kFrameHeaderBytes < n) break;
    const auto payload = stream.subspan(at + kFrameHeaderBytes, n);
    f.frames.emplace_back(payload.begin(), payload.end());
    at += kFrameHeaderBytes + n;
  }
  f.rest = stream.size() - at;
  return f;
}

// ---- seeds -------------------------------------------------------------------------------

PostureRecord sampleRecord(int joints, std::uint16_t sequence) {
  Posture p;
  p.root_translation = glm::vec3(0.25f, 1.0f, -0.5f);
  for (int j = 0; j < joints; ++j) {
    p.rotations.push_back(glm::angleAxis(0.2f * static_cast<float>(j), glm::vec3(0, 1, 0)));
  }
  PostureRecord record;
  encodePostureRecord(p, sequence, 12.5, record);
  return record;
}

// Appends the datagram of `packet` to the seeds, checking that it reads back.
template <typename Packet>
std::vector<std::uint8_t> addPacket(std::vector<fuzz::Seed>& seeds, const char* name,
                                    const Packet& packet) {
  std::vector<std::uint8_t> out;
  write(packet, out);
  Packet back;
  check(read(out, back), "a seed datagram reads back");
  seeds.push_back({name, out});
  return out;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  const ClientHeader header{7, 0x0123456789abcdefull};
  addPacket(seeds, "hello.bin", HelloPacket{header, 3, 0x0102030405060708ull});
  const auto posture =
      addPacket(seeds, "posture_5.bin", PosturePacket{header, sampleRecord(5, 42)});
  addPacket(seeds, "posture_52.bin", PosturePacket{header, sampleRecord(52, 65535)});
  addPacket(seeds, "ping.bin", PingPacket{header, 9, 1.25});
  addPacket(seeds, "hello_ack.bin", HelloAckPacket{7, 3, 0, 5});
  const std::vector<std::uint8_t> pong = addPacket(seeds, "pong.bin", PongPacket{9, 100.5, 6});
  // Sealed: what travels.
  std::vector<std::uint8_t> sealed = posture;
  check(sealDatagram(fuzzKey(), 11, kClientHeaderBytes, sealed), "a seed posture seals");
  seeds.push_back({"sealed_posture_5.bin", sealed});
  sealed = pong;
  check(sealDatagram(fuzzKey(), 12, kServerHeaderBytes, sealed), "a seed pong seals");
  seeds.push_back({"sealed_pong.bin", sealed});

  // A snapshot of two members, a prop and a two-part interaction list's first part.
  std::vector<std::uint8_t> snapshot, record, world;
  SnapshotHeader snapshot_header{77, 100.0, 0, 1, 0, 2, 0, 0, 13};
  beginSnapshot(snapshot_header, snapshot);
  writeRecord(sampleRecord(3, 1), record);
  appendSnapshotEntry(7, record, snapshot);
  record.clear();
  writeRecord(sampleRecord(1, 2), record);
  appendSnapshotEntry(8, record, snapshot);
  const PropStateRecord prop =
      encodePropState(0x00010000u, {0.0f, 1.2f, 0.5f}, {0.0f, -2.0f, 0.0f});
  InteractionSection section;
  section.member_ids = {7, 8};
  section.prop_ids = {0x00010000u};
  section.pairs = {{0, 1, 1, 2}, {0, 3, 2, 0}, {1, 5, 1, 9}};
  writeSnapshotWorld(std::span(&prop, 1), &section, world);
  appendSnapshotWorld(world, snapshot);
  finishSnapshot(2, snapshot);
  Snapshot read_back;
  check(readSnapshot(snapshot, read_back) && read_back.entries.size() == 2 &&
            read_back.interactions.pairs.size() == 3,
        "the seed snapshot reads back");
  seeds.push_back({"snapshot_2.bin", snapshot});
  sealed = snapshot;
  check(sealDatagram(fuzzKey(), 14, kServerHeaderBytes, sealed), "a seed snapshot seals");
  seeds.push_back({"sealed_snapshot_2.bin", sealed});

  // TCP streams: frames of datagram bytes, an empty frame, an oversized length.
  std::vector<std::uint8_t> stream;
  appendFrame(pong, stream);
  appendFrame({}, stream);
  appendFrame(snapshot, stream);
  check(frameAtOnce(stream).frames.size() == 3, "the seed stream has three frames");
  seeds.push_back({"stream_3frames.bin", stream});
  const std::vector<std::uint8_t> big(kMaxFrame + 1, 0x55);
  appendFrame(big, stream);
  seeds.push_back({"stream_oversized.bin", stream});
  return seeds;
}

// ---- datagrams ---------------------------------------------------------------------------

void checkRecord(const PostureRecord& record, double reference) {
  Posture p;
  decodePostureRecord(record, reference, p);
  check(p.rotations.size() == record.joint_count, "a rotation per joint");
  for (const glm::quat& q : p.rotations) {
    check(std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z),
          "decoded rotations are finite");
    check(std::abs(glm::length(q) - 1.0f) < 1e-4f, "decoded rotations are unit");
  }
  check(std::isfinite(p.root_translation.x) && std::isfinite(p.root_translation.y) &&
            std::isfinite(p.root_translation.z) && std::isfinite(p.time),
        "decoded root and time are finite");
}

// An accepted plain datagram seals (with a counter) and opens back to itself; with any
// byte changed it does not open.
void checkSealRoundTrip(std::span<const std::uint8_t> plain, PacketType type,
                        std::uint8_t flip_at) {
  const std::size_t clear = clearHeaderBytes(type);
  std::vector<std::uint8_t> sealed(plain.begin(), plain.end());
  check(sealDatagram(fuzzKey(), 1 + flip_at, clear, sealed), "an accepted datagram seals");
  check(sealed.size() == plain.size() + kAeadTagBytes, "sealing adds the tag");
  std::vector<std::uint8_t> opened = sealed;
  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  check(openDatagram(fuzzKey(), clear, opened, counter, plain_size), "a sealed datagram opens");
  check(counter == 1u + flip_at && plain_size == plain.size(), "opening gives counter and size");
  check(
      std::ranges::equal(std::span(opened).first(plain_size).subspan(clear), plain.subspan(clear)),
      "opening gives the body back");
  std::vector<std::uint8_t> bad = sealed;
  bad[flip_at % bad.size()] ^= 0x10;
  check(!openDatagram(fuzzKey(), clear, bad, counter, plain_size), "a changed byte is rejected");
}

// Opening arbitrary bytes: bounded, and only what was sealed with the key opens.
void checkOpen(std::span<const std::uint8_t> bytes) {
  for (std::size_t clear : {kClientHeaderBytes, kServerHeaderBytes}) {
    std::vector<std::uint8_t> buffer(bytes.begin(), bytes.end());
    std::uint64_t counter = 0;
    std::size_t plain_size = 0;
    if (!openDatagram(fuzzKey(), clear, buffer, counter, plain_size)) continue;
    check(plain_size + kAeadTagBytes == bytes.size(), "an opened datagram loses its tag only");
    check(counter == peekCounter(bytes, clear), "the counter is the clear header's");
    std::vector<std::uint8_t> again(buffer.begin(), buffer.begin() + static_cast<long>(plain_size));
    check(sealDatagram(fuzzKey(), counter, clear, again) && std::ranges::equal(again, bytes),
          "what opens seals back to the same bytes");
  }
}

// Reads the datagram as a Packet; when accepted, checks write/measure/peek agree.
template <typename Packet>
std::optional<Packet> readExactly(std::span<const std::uint8_t> bytes, PacketType type) {
  Packet packet;
  if (!read(bytes, packet)) return std::nullopt;
  checkSealRoundTrip(bytes, type, bytes.empty() ? 0 : bytes.back());
  std::vector<std::uint8_t> again;
  write(packet, again);
  check(std::ranges::equal(again, bytes), "an accepted datagram writes back to its bytes");
  check(measure(packet) == bytes.size(), "measure() is the datagram's size");
  check(peekPacketType(bytes) == type, "peekPacketType names the accepted type");
  return packet;
}

template <typename Packet>
void checkClientPacket(std::span<const std::uint8_t> bytes, PacketType type) {
  if (auto packet = readExactly<Packet>(bytes, type)) {
    check(peekMemberId(bytes) == packet->header.member_id, "peekMemberId is the header's");
  }
}

void checkDatagram(std::span<const std::uint8_t> bytes) {
  checkClientPacket<HelloPacket>(bytes, PacketType::kHello);
  checkClientPacket<PingPacket>(bytes, PacketType::kPing);
  (void)readExactly<HelloAckPacket>(bytes, PacketType::kHelloAck);
  (void)readExactly<PongPacket>(bytes, PacketType::kPong);
  if (auto posture = readExactly<PosturePacket>(bytes, PacketType::kPosture)) {
    check(peekMemberId(bytes) == posture->header.member_id, "peekMemberId is the header's");
    checkRecord(posture->record, 100.0);
  }

  Snapshot snapshot;
  if (readSnapshot(bytes, snapshot)) {
    const SnapshotHeader& header = snapshot.header;
    check(peekPacketType(bytes) == PacketType::kSnapshot, "peekPacketType says snapshot");
    check(snapshot.entries.size() == header.entry_count, "entry_count entries");
    check(snapshot.props.size() == header.prop_count, "prop_count props");
    std::size_t total = kSnapshotHeaderBytes + snapshot.props.size() * kPropStateBytes;
    for (const SnapshotEntry& e : snapshot.entries) {
      total += measure(e);
      checkRecord(e.record, header.server_time);
    }
    const InteractionSection& x = snapshot.interactions;
    if (header.part_count > 0) {
      total += interactionSectionBytes(x.bodyCount(), x.pairs.size());
      for (const WirePair& p : x.pairs) {
        check(p.body_a < x.bodyCount() && p.body_b < x.bodyCount(), "body indices in the table");
      }
    } else {
      check(x.bodyCount() == 0 && x.pairs.empty(), "no section without parts");
    }
    check(total == bytes.size(), "a snapshot's parts cover the datagram");
    check(measure(snapshot) == bytes.size(), "measure agrees with the bytes");
    std::vector<std::uint8_t> again;
    write(snapshot, again);
    check(std::ranges::equal(again, bytes), "what reads back writes the same bytes");
    checkSealRoundTrip(bytes, PacketType::kSnapshot, bytes.back());
  }
  checkOpen(bytes);
}

// ---- TCP framing -------------------------------------------------------------------------

void checkFraming(std::span<const std::uint8_t> stream) {
  const Framing expected = frameAtOnce(stream);
  FrameDecoder decoder(kMaxFrame);
  std::size_t frame = 0;
  bool broken = false;
  fuzz::feedInChunks(stream, stream.empty() ? 0u : stream[0], [&](auto piece) {
    if (broken) return;
    if (!decoder.push(piece)) {
      broken = true;
      return;
    }
    while (auto payload = decoder.next()) {
      check(frame < expected.frames.size(), "no more frames than the stream holds");
      check(std::ranges::equal(*payload, expected.frames[frame]), "frames arrive intact");
      ++frame;
    }
  });
  broken = broken || decoder.broken();
  check(broken == expected.broken, "the stream breaks exactly at an oversized length");
  check(!broken || !decoder.error().empty(), "a broken stream says why");
  check(frame == expected.frames.size(), "every complete frame is returned");
  if (!broken) check(decoder.buffered() == expected.rest, "the partial frame stays buffered");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  checkDatagram(bytes);
  checkFraming(bytes);
  return 0;
}
