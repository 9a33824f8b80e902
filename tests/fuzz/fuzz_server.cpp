// libFuzzer target: the session server's protocol core (server/core/server_core.hpp) fed by
// hostile peers: TCP control bytes (framing + protobuf), UDP datagrams and the passage of
// time, from four connections and four UDP endpoints.
//
// Input: a script of operations, each an op byte (bits 0-2: kind, bits 3-4: peer 0..3)
// and its operands:
//   0 connect                 1 stream bytes: u16 length, bytes     2 datagram: u16, bytes
//   3 disconnect              4 advance time by u8 * 5 ms, update    5 hello: u8 attempt
//   6 posture: u8 joints, u16 sequence, then 4 bytes per joint       7 ping: u32 id
// Hello, posture and ping use the member id of the peer's last Welcome and are sealed with
// its keys (proto/WIRE.md §3.9: what the fuzzer could not guess; taken from the lobby), with
// everything else from the input; raw datagrams (op 2) go as they are. Every operation also
// advances the clock by 1 ms. Closes the server asks for are carried out (onDisconnect).
// Properties: nothing crashes, throws, leaks or reads out of bounds; every frame the
// server writes is a well-formed ServerMessage, every datagram a server -> client packet
// of at most kMaxDatagramBytes sealed with its recipient's key that opens to a well-formed
// packet.
// Seeds: scripted sessions (join with an avatar upload, a second member reusing the
// avatar, hellos, postures, pings, requests, a ball spawn, leaving) written by the same
// encoder. The avatar carries an implicit model and the rooms start with a ball, so every
// tick runs the collision world (posing, stepBall, Step 1, world parts).
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <span>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "common/avatar/avatar_io.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/framing.hpp"
#include "common/wire/packets.hpp"
#include "control.pb.h"
#include "server/core/server_config.hpp"
#include "server/core/server_core.hpp"
#include "tests/fuzz/fuzz_support.hpp"
#include "tests/fuzz/tiny_avatar.hpp"
#include "tests/net/implicit_avatar.hpp"

namespace {

// The last challenge each address got (WIRE.md §3.2), so that scripted hellos can bind.
std::map<std::string, std::uint64_t>& challenges() {
  static std::map<std::string, std::uint64_t> cookies;
  return cookies;
}

using namespace vistel;
using fuzz::check;

constexpr int kPeers = 4;
constexpr int kMaxOps = 400;

enum Op : std::uint8_t {
  kConnect = 0,
  kStream = 1,
  kDatagram = 2,
  kDisconnect = 3,
  kAdvance = 4,
  kHello = 5,
  kPosture = 6,
  kPing = 7,
};

// ---- reading the script ------------------------------------------------------------------

class Script {
 public:
  explicit Script(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  bool done() const { return at_ >= bytes_.size(); }
  std::uint8_t u8() { return done() ? 0 : bytes_[at_++]; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() { return u16() | (static_cast<std::uint32_t>(u16()) << 16); }
  std::span<const std::uint8_t> take(std::size_t n) {
    n = std::min(n, bytes_.size() - at_);
    const auto s = bytes_.subspan(at_, n);
    at_ += n;
    return s;
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

// ---- writing scripts (seeds) -------------------------------------------------------------

class ScriptWriter {
 public:
  void op(Op kind, int peer) { out_.push_back(static_cast<std::uint8_t>(kind | (peer << 3))); }
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    u16(static_cast<std::uint16_t>(v));
    u16(static_cast<std::uint16_t>(v >> 16));
  }
  void bytes(std::span<const std::uint8_t> b) {
    u16(static_cast<std::uint16_t>(b.size()));
    out_.insert(out_.end(), b.begin(), b.end());
  }
  void message(int peer, const control::ClientMessage& msg) {
    const std::string payload = msg.SerializeAsString();
    std::vector<std::uint8_t> frame;
    wire::appendFrame({reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()},
                      frame);
    op(kStream, peer);
    bytes(frame);
  }
  void hello(int peer) {
    op(kHello, peer);
    u8(1);  // attempt
  }
  void advance(int peer, std::uint8_t steps) {
    op(kAdvance, peer);
    u8(steps);
  }
  void posture(int peer, std::uint8_t joints, std::uint16_t sequence) {
    op(kPosture, peer);
    u8(joints);
    u16(sequence);
    for (int j = 0; j < joints; ++j) u32(wire::packQuat(glm::quat(1.0f, 0.0f, 0.0f, 0.0f)));
  }
  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  std::vector<std::uint8_t> out_;
};

control::ClientMessage joinMessage(const std::string& name, const std::string& hash,
                                   std::size_t size) {
  control::ClientMessage msg;
  control::Join& join = *msg.mutable_join();
  join.set_protocol_version(server::kProtocolVersion);
  join.set_room("fuzz.room");
  join.set_name(name);
  join.set_avatar_hash(hash);
  join.set_avatar_size(size);
  // A valid X25519 public key (RFC 7748 §6.1, Alice's); the fuzzer's peers take their
  // session keys from the lobby.
  join.set_udp_public_key(std::string{
      '\x85', '\x20', '\xf0', '\x09', '\x89', '\x30', '\xa7', '\x54', '\x74', '\x8b', '\x7d',
      '\xdc', '\xb4', '\x3e', '\xf7', '\x5a', '\x0d', '\xbf', '\x3a', '\x0d', '\x26', '\x38',
      '\x1a', '\xf4', '\xeb', '\xa4', '\xa9', '\x8e', '\xaa', '\x9b', '\x4e', '\x6a'});
  return msg;
}

// The tiny avatar with primitives on its three joints (so members collide).
AvatarModel collidingAvatar() {
  AvatarModel a = fuzz::tinyAvatar(3, 2);
  check(test::addImplicitModel(a, 0.08f, 1.6f), "the seed avatar calibrates");
  return a;
}

std::vector<fuzz::Seed> makeSeeds() {
  const std::vector<std::uint8_t> avatar = encodeAvatar(collidingAvatar());
  const std::string hash = avatarContentHash(avatar);
  const int joints = 3;

  // One member: join, upload in two chunks, hello, postures, pings, time, leave.
  ScriptWriter one;
  one.op(kConnect, 0);
  one.message(0, joinMessage("alice", hash, avatar.size()));
  for (std::size_t offset = 0; offset < avatar.size(); offset += 400) {
    control::ClientMessage chunk;
    control::AvatarChunk& c = *chunk.mutable_avatar_chunk();
    c.set_hash(hash);
    c.set_total_size(avatar.size());
    c.set_offset(offset);
    c.set_data(reinterpret_cast<const char*>(avatar.data()) + offset,
               std::min<std::size_t>(400, avatar.size() - offset));
    one.message(0, chunk);
  }
  one.hello(0);
  one.hello(0);  // echoes the challenge: bound
  control::ClientMessage spawn;
  spawn.mutable_spawn_prop()->set_kind(control::SpawnProp::BALL);
  one.message(0, spawn);
  // Dents of the first member's avatar (the first handle of a fresh pool) and of a prop.
  control::ClientMessage dents;
  control::Dents& d = *dents.mutable_dents();
  d.set_body_id(0x00010000u);
  d.set_vertex_count(64);
  d.set_server_time(0.5);
  for (std::uint32_t k = 0; k < 4; ++k) {
    d.add_gaps(k);
    d.add_depths(10 * (k + 1));
  }
  one.message(0, dents);
  d.set_prop(true);
  one.message(0, dents);
  one.posture(0, joints, 1);
  one.advance(0, 4);
  one.posture(0, joints, 2);
  one.op(kPing, 0);
  one.u32(7);
  one.advance(0, 20);
  const std::vector<std::uint8_t> joined = one.take();
  control::ClientMessage leave;
  leave.mutable_leave()->set_reason("done");
  one.message(0, leave);
  std::vector<std::uint8_t> single = joined;
  const std::vector<std::uint8_t> left = one.take();
  single.insert(single.end(), left.begin(), left.end());

  // Two members sharing the avatar; the second fetches it; one disconnects, time runs out.
  ScriptWriter two;
  two.op(kConnect, 1);
  two.message(1, joinMessage("bob", hash, avatar.size()));
  two.hello(1);
  two.hello(1);
  two.posture(1, joints, 9);
  control::ClientMessage request;
  request.mutable_avatar_request()->set_hash(hash);
  two.message(1, request);
  two.advance(1, 200);
  two.op(kDisconnect, 0);
  two.advance(1, 255);
  two.advance(1, 255);
  std::vector<std::uint8_t> pair = joined;
  const std::vector<std::uint8_t> rest = two.take();
  pair.insert(pair.end(), rest.begin(), rest.end());

  // Bad first messages: garbage frame, a wrong protocol version, an oversized length.
  ScriptWriter bad;
  bad.op(kConnect, 2);
  control::ClientMessage wrong = joinMessage("eve", hash, avatar.size());
  wrong.mutable_join()->set_protocol_version(99);
  bad.message(2, wrong);
  bad.op(kConnect, 3);
  const std::uint8_t huge[] = {0xff, 0xff, 0xff, 0x7f, 1, 2, 3};
  bad.op(kStream, 3);
  bad.bytes(huge);
  bad.op(kDatagram, 3);
  bad.bytes(huge);

  return {{"one_member.bin", single}, {"two_members.bin", pair}, {"bad_peers.bin", bad.take()}};
}

// ---- the run -----------------------------------------------------------------------------

struct Peer {
  server::ConnId conn = 0;  // 0: not connected
  bool welcomed = false;
  std::uint32_t member_id = 0;
  std::uint64_t counter = 0;  // the last uplink counter used
  wire::Endpoint endpoint;
};

// Seals a peer's datagram as its client would (no keys, e.g. before a Welcome: as is).
void sealFor(const server::ServerCore& core, Peer& peer, std::vector<std::uint8_t>& datagram) {
  if (const wire::SessionKeys* keys = core.lobby().keysOf(peer.member_id)) {
    wire::sealDatagram(keys->client_to_server, ++peer.counter, wire::kClientHeaderBytes, datagram);
  }
}

// Checks what the server asked to send, learns Welcomes, carries out closes. With
// VISTEL_FUZZ_TRACE set, prints what it sees (to follow a crashing input).
void drain(server::ServerCore& core, std::array<Peer, kPeers>& peers, double now) {
  static const bool trace = std::getenv("VISTEL_FUZZ_TRACE") != nullptr;
  for (int round = 0; round < 4 && !core.effects().empty(); ++round) {
    server::Effects fx;
    std::swap(fx, core.effects());
    for (const server::OutFrame& f : fx.frames) {
      std::span<const std::uint8_t> rest(f.bytes);
      while (!rest.empty()) {
        check(rest.size() >= wire::kFrameHeaderBytes, "whole frames only");
        const std::uint32_t n = fuzz::loadU32(rest.data());
        check(rest.size() - wire::kFrameHeaderBytes >= n, "whole frames only");
        control::ServerMessage msg;
        check(msg.ParseFromArray(rest.data() + wire::kFrameHeaderBytes, static_cast<int>(n)),
              "frames hold ServerMessages");
        rest = rest.subspan(wire::kFrameHeaderBytes + n);
        if (trace)
          std::printf("%.3f conn %llu <- %s\n", now, static_cast<unsigned long long>(f.conn),
                      msg.ShortDebugString().substr(0, 160).c_str());
        if (!msg.has_welcome()) continue;
        for (Peer& p : peers) {
          if (p.conn != f.conn) continue;
          p.welcomed = true;
          p.member_id = msg.welcome().member_id();
          p.counter = 0;
        }
      }
    }
    for (const server::OutDatagram& sealed : fx.datagrams) {
      check(sealed.bytes.size() <= wire::kMaxDatagramBytes, "datagrams fit kMaxDatagramBytes");
      const auto type = wire::peekPacketType(sealed.bytes);
      check(type.has_value(), "datagrams have a known type");
      if (trace)
        std::printf("%.3f %s <- datagram type %#x, %zu bytes\n", now, sealed.to.toString().c_str(),
                    static_cast<unsigned>(*type), sealed.bytes.size());
      // Open it with the recipient's keys (a peer's member); skipped when the member is gone.
      const wire::SessionKeys* keys = nullptr;
      for (const Peer& p : peers) {
        if (p.endpoint == sealed.to && p.member_id != 0) keys = core.lobby().keysOf(p.member_id);
      }
      if (keys == nullptr) continue;
      server::OutDatagram d{sealed.to, sealed.bytes};
      std::uint64_t counter = 0;
      std::size_t plain_size = 0;
      check(wire::openDatagram(
                *type == wire::PacketType::kHelloAck ? keys->server_hello : keys->server_to_client,
                wire::kServerHeaderBytes, d.bytes, counter, plain_size),
            "datagrams are sealed with their recipient's key");
      d.bytes.resize(plain_size);
      if (*type == wire::PacketType::kHelloAck) {
        wire::HelloAckPacket p;
        check(wire::read(d.bytes, p), "HelloAck reads back");
        challenges()[d.to.toString()] = p.cookie;  // the next hello from there echoes it
      } else if (*type == wire::PacketType::kPong) {
        wire::PongPacket p;
        check(wire::read(d.bytes, p), "Pong reads back");
      } else {
        check(*type == wire::PacketType::kSnapshot, "only client-bound datagrams");
        static wire::Snapshot snapshot;
        check(wire::readSnapshot(d.bytes, snapshot), "snapshots read back");
      }
    }
    for (server::ConnId conn : fx.closes) {
      if (trace)
        std::printf("%.3f conn %llu closed by the server\n", now,
                    static_cast<unsigned long long>(conn));
      for (Peer& p : peers) {
        if (p.conn == conn) p = Peer{0, false, 0, 0, p.endpoint};
      }
      core.onDisconnect(conn, now);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  spdlog::set_level(spdlog::level::off);
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  server::ServerConfig config;
  config.max_avatar_bytes = 1u << 16;
  config.avatar_chunk_bytes = 4096;
  config.max_members_per_room = 3;
  config.max_rooms = 2;
  config.max_props_per_room = 3;
  config.spawn_interval_s = 0.01;
  server::RoomPropConfig ball;
  ball.position = {0.0f, 1.0f, 0.0f};
  config.room_props.push_back(ball);
  server::ServerCore core(config, 1);

  std::array<Peer, kPeers> peers;
  for (int i = 0; i < kPeers; ++i) {
    peers[i].endpoint = wire::Endpoint::ipv4(0x0A000001u + static_cast<std::uint32_t>(i),
                                             static_cast<std::uint16_t>(5000 + i));
  }
  server::ConnId next_conn = 1;
  double now = 1000.0;
  Script script({data, size});
  std::vector<std::uint8_t> datagram;

  for (int ops = 0; ops < kMaxOps && !script.done(); ++ops) {
    const std::uint8_t code = script.u8();
    Peer& peer = peers[(code >> 3) % kPeers];
    now += 0.001;
    switch (static_cast<Op>(code & 7)) {
      case kConnect:
        if (peer.conn == 0) {
          peer.conn = next_conn++;
          core.onConnect(peer.conn, now);
        }
        break;
      case kStream: {
        const auto bytes = script.take(script.u16());
        if (peer.conn != 0) core.onStreamBytes(peer.conn, bytes, now);
        break;
      }
      case kDatagram:
        core.onDatagram(script.take(script.u16()), peer.endpoint, now);
        break;
      case kDisconnect:
        if (peer.conn != 0) {
          core.onDisconnect(peer.conn, now);
          peer = Peer{0, false, 0, 0, peer.endpoint};
        }
        break;
      case kAdvance:
        now += 0.005 * script.u8();
        core.update(now);
        break;
      case kHello:
        datagram.clear();
        wire::write(
            wire::HelloPacket{
                {peer.member_id, 0}, script.u8(), challenges()[peer.endpoint.toString()]},
            datagram);
        sealFor(core, peer, datagram);
        core.onDatagram(datagram, peer.endpoint, now);
        break;
      case kPosture: {
        wire::PosturePacket p{{peer.member_id, 0}, {}};
        p.record.joint_count = script.u8();
        p.record.sequence = script.u16();
        p.record.time = wire::toWireTime(now);
        for (int j = 0; j < p.record.joint_count; ++j) p.record.rotations[j] = script.u32();
        datagram.clear();
        wire::write(p, datagram);
        sealFor(core, peer, datagram);
        core.onDatagram(datagram, peer.endpoint, now);
        break;
      }
      case kPing:
        datagram.clear();
        wire::write(wire::PingPacket{{peer.member_id, 0}, script.u32(), now - 0.01}, datagram);
        sealFor(core, peer, datagram);
        core.onDatagram(datagram, peer.endpoint, now);
        break;
    }
    drain(core, peers, now);
  }
  core.shutdown(now + 1.0);
  drain(core, peers, now + 1.0);
  return 0;
}
