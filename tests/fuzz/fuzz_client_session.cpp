// libFuzzer target: the client's session core (client/net/client_session.hpp) fed by a
// hostile server: control-channel bytes (framing + protobuf ServerMessages), UDP datagrams
// (hello acks, pongs, snapshots with postures, props and interaction parts) and the
// passage of time, while the participant sends postures and asks for balls.
//
// Input: a script of operations, each an op byte (bits 0-2: kind, bits 3-7: operand) and
// its operands:
//   0 stream bytes: u16 length, bytes      1 datagram: u16 length, bytes
//   2 advance time by (op >> 3) + 1 ms, then update; with op bit 7 set by u8 * 100 ms
//   3 send a posture (joint count from the op: the avatar's, or a wrong one)
//   4 request a ball                       5 map the interactions onto a scene
//   6 the TCP connection drops              7 leave
// A session starts (sends its Join) before the script; every operation advances the clock
// by 1 ms. Properties: nothing crashes, throws, leaks or reads out of bounds; the state
// never goes back (joining -> handshaking -> live -> closed); what the session sends is
// well formed: whole frames of ClientMessages, client -> server datagrams of at most
// kMaxDatagramBytes; nothing is sent once closed; sampling every member's posture and
// every prop's state at any time is safe; the scene mapping of interactions fails or
// succeeds cleanly.
//
// The victim's UDP key pair is fixed (SessionSettings::fixed_udp_private_key), so the
// recorded datagrams, sealed for it, open in every replay; mutated ones mostly do not.
//
// Seeds: what a real ServerCore sent to one client (the "victim") in a session with a
// second member: the Welcome after the avatar upload, the hello ack, pongs, rosters, the
// other member's avatar (fetched), snapshots of its postures, a ball and the interaction
// lists of their contacts; the same session cut once the victim is live, then the
// connection lost; and a join refused (wrong protocol version).
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "client/net/client_session.hpp"
#include "common/anim/posture.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/wire/framing.hpp"
#include "common/wire/packets.hpp"
#include "control.pb.h"
#include "server/core/server_config.hpp"
#include "server/core/server_core.hpp"
#include "tests/fuzz/fuzz_support.hpp"
#include "tests/fuzz/tiny_avatar.hpp"
#include "tests/net/implicit_avatar.hpp"

namespace {

using namespace vistel;
using fuzz::check;
using net::PropSample;

constexpr int kMaxOps = 3000;

enum Op : std::uint8_t {
  kStream = 0,
  kDatagram = 1,
  kAdvance = 2,
  kPosture = 3,
  kBall = 4,
  kScene = 5,
  kDisconnect = 6,
  kLeave = 7,
};

// ---- the avatars -------------------------------------------------------------------------

struct EncodedAvatar {
  std::vector<std::uint8_t> bytes;
  std::string hash;
  int joints = 0;
};

// A tiny avatar with primitives on its joints (so members and balls collide).
EncodedAvatar collidingAvatar(int joints, float radius) {
  AvatarModel a = fuzz::tinyAvatar(joints, 2);
  check(test::addImplicitModel(a, radius, 1.6f), "the seed avatar calibrates");
  EncodedAvatar e;
  e.bytes = encodeAvatar(a);
  e.hash = avatarContentHash(e.bytes);
  e.joints = joints;
  return e;
}

// The victim's avatar, the same in the seeds and in every run.
const EncodedAvatar& ownAvatar() {
  static const EncodedAvatar avatar = collidingAvatar(3, 0.08f);
  return avatar;
}

net::SessionSettings settingsFor(const std::string& name, const EncodedAvatar& avatar) {
  net::SessionSettings s;
  s.room = "fuzz.room";
  s.name = name;
  s.avatar_bytes = std::make_shared<const std::vector<std::uint8_t>>(avatar.bytes);
  s.avatar_hash = avatar.hash;
  s.avatar_joint_count = avatar.joints;
  s.max_avatar_bytes = 1u << 16;
  s.max_frame_bytes = 1u << 17;
  // The same UDP key pair in the capture and every replay, so that the recorded Welcome
  // gives the keys the recorded datagrams were sealed with (proto/WIRE.md §3.9).
  for (std::size_t i = 0; i < s.fixed_udp_private_key.size(); ++i) {
    s.fixed_udp_private_key[i] = static_cast<std::uint8_t>(name.size() * 31 + i + 1);
  }
  return s;
}

// A posture of `joints` joints, turned by `angle` about +Y at every joint.
Posture postureOf(int joints, float angle) {
  Posture p;
  p.rotations.assign(static_cast<std::size_t>(joints),
                     glm::angleAxis(angle, glm::vec3(0.0f, 1.0f, 0.0f)));
  p.root_translation = glm::vec3(0.0f, 0.9f, 0.0f);
  return p;
}

// ---- writing scripts (seeds) -------------------------------------------------------------

class ScriptWriter {
 public:
  explicit ScriptWriter(double start) : clock_(start) {}
  void op(Op kind, std::uint8_t operand = 0) {
    out_.push_back(static_cast<std::uint8_t>(kind | (operand << 3)));
    clock_ += 0.001;
  }
  void bytes(Op kind, std::span<const std::uint8_t> b) {
    op(kind);
    out_.push_back(static_cast<std::uint8_t>(b.size()));
    out_.push_back(static_cast<std::uint8_t>(b.size() >> 8));
    for (std::uint8_t byte : b) out_.push_back(byte);  // (insert() trips GCC 12's -Wstringop)
  }
  // Advances the replay's clock to `t` (each operation costs 1 ms, an advance operation
  // 1 + (2..33) ms), so that what follows arrives when it did in the capture.
  void advanceTo(double t) {
    int ms = static_cast<int>((t - clock_) * 1000.0 + 0.5);
    while (ms >= 2) {
      const int step = std::min(ms - 1, 32);
      op(kAdvance, static_cast<std::uint8_t>(step - 1));
      clock_ += 0.001 * step;
      ms -= step + 1;
    }
  }
  std::size_t size() const { return out_.size(); }
  const std::vector<std::uint8_t>& bytes() const { return out_; }

 private:
  std::vector<std::uint8_t> out_;
  double clock_;  // the replay's clock after the operations so far
};

constexpr double kStart = 100.0;  // the session's clock when it starts

// A session between a real server and two clients over a perfect network, 5 ms a step;
// everything the server sends the victim (client 0) is written into the script, with the
// victim's own actions. Returns the script and where in it the victim went live.
struct Capture {
  std::vector<std::uint8_t> script;
  std::size_t welcomed_at = 0;  // script length once the victim is live
};

Capture captureSession(int steps) {
  server::ServerConfig config;
  config.max_avatar_bytes = 1u << 16;
  config.avatar_chunk_bytes = 1024;
  config.max_members_per_room = 4;
  config.spawn_interval_s = 0.01;
  config.tick_rate_hz = 30.0;
  server::ServerCore core(config, 7);

  const EncodedAvatar other = collidingAvatar(2, 0.1f);
  auto cache = std::make_shared<net::AvatarCache>();
  std::array<std::unique_ptr<net::ClientSession>, 2> clients = {
      std::make_unique<net::ClientSession>(settingsFor("victim", ownAvatar()), cache),
      std::make_unique<net::ClientSession>(settingsFor("other", other),
                                           std::make_shared<net::AvatarCache>())};
  const std::array<server::ConnId, 2> conns = {1, 2};
  const std::array<wire::Endpoint, 2> endpoints = {wire::Endpoint::ipv4(0x0A000001u, 40000),
                                                   wire::Endpoint::ipv4(0x0A000002u, 40001)};

  ScriptWriter script(kStart);
  Capture capture;
  double now = kStart;
  const auto pump = [&] {
    for (int round = 0; round < 4; ++round) {
      for (std::size_t i = 0; i < clients.size(); ++i) {
        net::SessionOutbox& out = clients[i]->outbox();
        if (!out.stream.empty()) core.onStreamBytes(conns[i], out.stream, now);
        for (const auto& d : out.datagrams) core.onDatagram(d, endpoints[i], now);
        out.clear();
      }
      server::Effects fx;
      std::swap(fx, core.effects());
      for (const server::OutFrame& f : fx.frames) {
        const std::size_t i = f.conn == conns[0] ? 0 : 1;
        if (i == 0) {
          script.advanceTo(now);
          // Frames go in pieces of at most 4 KB (a u16 length; the avatar arrives in chunks).
          for (std::size_t at = 0; at < f.bytes.size(); at += 4096) {
            script.bytes(kStream, std::span(f.bytes).subspan(
                                      at, std::min<std::size_t>(4096, f.bytes.size() - at)));
          }
        }
        clients[i]->onStreamBytes(f.bytes, now);
      }
      for (const server::OutDatagram& d : fx.datagrams) {
        const std::size_t i = d.to == endpoints[0] ? 0 : 1;
        if (i == 0) {
          script.advanceTo(now);
          script.bytes(kDatagram, d.bytes);
        }
        clients[i]->onDatagram(d.bytes, now);
      }
      for (server::ConnId conn : fx.closes) core.onDisconnect(conn, now);
    }
  };

  for (std::size_t i = 0; i < clients.size(); ++i) {
    core.onConnect(conns[i], now);
    clients[i]->start(now);
  }
  pump();
  for (int step = 0; step < steps; ++step) {
    now += 0.005;
    core.update(now);
    for (auto& c : clients) c->update(now);
    // Postures from both at about 50 Hz, a ball from the other member after 0.3 s, its dents
    // after 0.6 s.
    if (step % 4 == 0) {
      const float angle = 0.05f * static_cast<float>(step);
      if (clients[0]->sendPosture(postureOf(ownAvatar().joints, angle), now)) {
        script.advanceTo(now);
        script.op(kPosture, 1);
      }
      clients[1]->sendPosture(postureOf(other.joints, -angle), now);
    }
    if (step == 60) clients[1]->requestBall();
    if (step == 90) {
      script.op(kBall);
      clients[0]->requestBall();
    }
    if (step == 120) {  // the other member's dents, relayed to us (SESSION.md §2.5)
      net::BodyDents dents;
      dents.body_id = clients[1]->memberId();
      dents.server_time = now;
      dents.record.vertex_count = 64;
      dents.record.gaps = {2, 0, 5};
      dents.record.depths = {10, 25, 3};
      clients[1]->sendDents(dents);
    }
    pump();
    if (capture.welcomed_at == 0 && clients[0]->state() == net::SessionState::kLive) {
      capture.welcomed_at = script.size();
    }
    if (step % 20 == 10) script.op(kScene);
  }
  check(clients[0]->state() == net::SessionState::kLive, "the seed session goes live");
  check(clients[0]->members().size() == 2, "the seed session sees the other member");
  capture.script = script.bytes();
  return capture;
}

// What a run of a script left (for checking the seeds).
struct Outcome {
  net::SessionState state = net::SessionState::kJoining;
  std::size_t members = 0;
  std::size_t props = 0;
  std::uint64_t interactions = 0;  // lists received
  std::uint64_t dents = 0;         // Dents received (well formed)
};
Outcome runScript(std::span<const std::uint8_t> bytes);

std::vector<fuzz::Seed> makeSeeds() {
  spdlog::set_level(spdlog::level::off);
  const Capture full = captureSession(240);  // 1.2 s: avatars, postures, a ball, contacts
  std::vector<std::uint8_t> cut(
      full.script.begin(), full.script.begin() + static_cast<std::ptrdiff_t>(full.welcomed_at));
  cut.push_back(kAdvance | (31 << 3));
  cut.push_back(kDisconnect);
  // The replay opens the recorded (sealed) datagrams: the other member's postures, the
  // ball and the contact lists all arrive.
  const Outcome replayed = runScript(full.script);
  check(replayed.members == 2 && replayed.props >= 1 && replayed.interactions > 0 &&
            replayed.dents == 1,
        "the seed session replays with its datagrams opened and the other member's dents");

  // A refusal: the server's ErrorReply to a join of a protocol it does not speak.
  control::ServerMessage refusal;
  refusal.mutable_error()->set_code(control::ErrorReply::VERSION_MISMATCH);
  refusal.mutable_error()->set_message("protocol version 99 is not supported");
  const std::string payload = refusal.SerializeAsString();
  std::vector<std::uint8_t> frame;
  wire::appendFrame({reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()}, frame);
  ScriptWriter refused(kStart);
  refused.advanceTo(kStart + 0.01);
  refused.bytes(kStream, frame);
  refused.advanceTo(kStart + 0.2);
  refused.op(kLeave);

  return {
      {"session.bin", full.script}, {"cut_when_live.bin", cut}, {"refused.bin", refused.bytes()}};
}

// ---- the run -----------------------------------------------------------------------------

class Script {
 public:
  explicit Script(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  bool done() const { return at_ >= bytes_.size(); }
  std::uint8_t u8() { return done() ? 0 : bytes_[at_++]; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
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

// Checks what the session asked to send, and forgets it.
void drain(net::ClientSession& session, bool was_closed) {
  net::SessionOutbox& out = session.outbox();
  if (was_closed) {
    check(out.stream.empty() && out.datagrams.empty(), "nothing is sent once closed");
  }
  std::span<const std::uint8_t> rest(out.stream);
  while (!rest.empty()) {
    check(rest.size() >= wire::kFrameHeaderBytes, "whole frames only");
    const std::uint32_t n = fuzz::loadU32(rest.data());
    check(rest.size() - wire::kFrameHeaderBytes >= n, "whole frames only");
    control::ClientMessage msg;
    check(msg.ParseFromArray(rest.data() + wire::kFrameHeaderBytes, static_cast<int>(n)),
          "frames hold ClientMessages");
    rest = rest.subspan(wire::kFrameHeaderBytes + n);
  }
  for (const std::vector<std::uint8_t>& d : out.datagrams) {
    check(d.size() <= wire::kMaxDatagramBytes, "datagrams fit kMaxDatagramBytes");
    const auto type = wire::peekPacketType(d);
    check(type == wire::PacketType::kHello || type == wire::PacketType::kPosture ||
              type == wire::PacketType::kPing,
          "only server-bound datagrams");
  }
  out.clear();
}

// Reads what the session holds, the way the client's render thread does.
void sample(const net::ClientSession& session, double now, Posture& posture) {
  const double server_now = session.serverTime(now);
  for (const auto& m : session.members()) {
    check(m != nullptr, "roster entries exist");
    check(session.findMember(m->id) != nullptr, "findMember finds roster entries");
    for (double dt : {-1.0, -0.1, 0.0, 0.5}) session.samplePosture(m->id, server_now + dt, posture);
  }
  for (const auto& p : session.props()) {
    check(p != nullptr && session.findProp(p->id) != nullptr, "findProp finds props");
    PropSample s;
    for (double dt : {-1.0, -0.1, 0.0, 0.5}) session.sampleProp(p->id, server_now + dt, s);
  }
  session.samplePosture(0xffffffffu, server_now, posture);
}

Outcome runScript(std::span<const std::uint8_t> bytes) {
  auto cache = std::make_shared<net::AvatarCache>();
  net::ClientSession session(settingsFor("victim", ownAvatar()), cache);
  double now = kStart;
  session.start(now);
  drain(session, false);

  Script script(bytes);
  Posture posture;
  InteractionList interactions;
  std::vector<BodyView> bodies;
  int state = static_cast<int>(session.state());
  for (int ops = 0; ops < kMaxOps && !script.done(); ++ops) {
    const std::uint8_t code = script.u8();
    const bool was_closed = session.state() == net::SessionState::kClosed;
    now += 0.001;
    switch (static_cast<Op>(code & 7)) {
      case kStream:
        session.onStreamBytes(script.take(script.u16()), now);
        break;
      case kDatagram:
        session.onDatagram(script.take(script.u16()), now);
        break;
      case kAdvance:
        now += (code & 0x80) != 0 ? 0.1 * script.u8() : 0.001 * ((code >> 3) + 1);
        session.update(now);
        break;
      case kPosture: {
        const int joints = (code >> 3) == 1 ? ownAvatar().joints : (code >> 3);
        session.sendPosture(postureOf(joints, 0.01f * static_cast<float>(ops)), now);
        break;
      }
      case kBall:
        session.requestBall();
        break;
      case kScene: {
        // Every body absent (pairs dropped), then none at all.
        bodies.assign(session.members().size() + session.props().size(), BodyView{});
        int dropped = 0;
        const Status mapped = session.sceneInteractions(bodies, interactions, &dropped);
        check(mapped.ok() || interactions.pairs.empty(), "a failed mapping leaves the list empty");
        check(dropped >= 0, "dropped pairs counted");
        const Status none = session.sceneInteractions({}, interactions, nullptr);
        check(none.ok() || interactions.pairs.empty(), "a failed mapping leaves the list empty");
        break;
      }
      case kDisconnect:
        session.onDisconnected("fuzz: connection lost", now);
        break;
      case kLeave:
        session.leave("fuzz: leaving");
        break;
    }
    const int next = static_cast<int>(session.state());
    check(next >= state, "the session state never goes back");
    state = next;
    // Leave() itself sends the Leave frame as it closes; after that, nothing.
    drain(session, was_closed);
    sample(session, now, posture);
  }
  return {session.state(), session.members().size(), session.props().size(),
          session.interactionsVersion(), session.stats().dents_received};
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  spdlog::set_level(spdlog::level::off);
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  runScript({data, size});
  return 0;
}
