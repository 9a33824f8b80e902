// libFuzzer target: whole sessions as a hostile network and a hostile peer make them. The
// real state machines of three participants (ClientSession) and the server (ServerCore)
// run over the in-process simulated network (tests/net/sim_network.hpp) while the input
// cuts and restarts connections, degrades links, and forges, mutates and replays the
// datagrams the participants send.
//
// Input: a script of operations, each an op byte (bits 0-2: kind, bits 3-4: participant
// 0..2, 3 meaning 2) and its operands:
//   0 advance u8: (n + 1) * 5 ms, every live participant sending postures at 30 Hz
//   1 link u8 loss, u8 duplicates, u8 jitter: its links both ways become
//     loss n / 510, duplicates n / 1275, jitter n * 0.4 ms (latency 10 ms)
//   2 cut: its TCP connection dies          3 restart: a new session on a new connection
//   4 forge u8 which, u8 where, u8 xor: one of the last 32 datagrams sent, a byte changed,
//     sent from the participant's address (bit 7 of which: from a stranger's)
//   5 replay u8 which: one of the last 32 datagrams sent, unchanged, from the participant's
//     address (bit 7: from the next participant's)
//   6 garbage u8 length, bytes: a datagram from the participant's address
//   7 stall u8: (n + 1) * 50 ms with no postures sent (timeouts and keepalives)
// At most kMaxOps operations and kMaxTime simulated seconds are run.
//
// Properties: nothing crashes or reads out of bounds; the server never holds more members
// than there are participants (forged and replayed datagrams make none); and after the
// script, with clean links, a restart of whoever has no session and two seconds of
// traffic, every participant is live, sees the two others, and receives their postures:
// no member is lost that did not leave.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "tests/fuzz/fuzz_support.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel {
namespace {

using fuzz::check;

constexpr int kParticipants = 3;
constexpr int kMaxOps = 96;
constexpr double kMaxTime = 20.0;  // simulated seconds of script
constexpr double kStep = 0.005;    // simulation step, seconds
constexpr double kSendEvery = 1.0 / 30.0;
constexpr std::size_t kSeen = 32;  // datagrams kept for forging and replaying

enum Op : std::uint8_t {
  kAdvance = 0,
  kLink = 1,
  kCut = 2,
  kRestart = 3,
  kForge = 4,
  kReplay = 5,
  kGarbage = 6,
  kStall = 7,
};

server::ServerConfig serverConfig() {
  server::ServerConfig c;
  c.tick_rate_hz = 30.0;
  c.member_timeout_s = 5.0;
  return c;
}

const test::EncodedAvatar& avatar() {
  static const test::EncodedAvatar a = test::encodeSynthetic(test::makeSyntheticAvatar());
  return a;
}

net::SessionSettings settingsOf(int i) {
  std::string name = "p";
  name += static_cast<char>('0' + i);  // (not "p" + to_string: GCC 12's -Wrestrict misfires)
  return test::sessionFor("fuzz", name, avatar(), 5);
}

// Reads operands; past the end of the input they are 0.
struct Reader {
  std::span<const std::uint8_t> in;
  std::size_t at = 0;
  bool done() const { return at >= in.size(); }
  std::uint8_t u8() { return at < in.size() ? in[at++] : 0; }
};

class Run {
 public:
  Run() : net_(serverConfig(), 7) {
    for (int i = 0; i < kParticipants; ++i) {
      net_.addClient(settingsOf(i), test::SimLink{}, test::SimLink{}, 0.25 * i);
    }
    net_.sniff(true);
    for (int i = 0; i < kParticipants; ++i) net_.connect(static_cast<std::size_t>(i));
  }

  void script(std::span<const std::uint8_t> data) {
    Reader r{data};
    for (int n = 0; n < kMaxOps && !r.done() && net_.now() < kMaxTime; ++n) {
      const std::uint8_t op = r.u8();
      const int who = std::min((op >> 3) & 3, kParticipants - 1);
      const auto w = static_cast<std::size_t>(who);
      switch (static_cast<Op>(op & 7)) {
        case kAdvance:
          advance((r.u8() + 1) * 0.005, true);
          break;
        case kLink: {
          test::SimLink link;
          link.loss = r.u8() / 510.0;
          link.duplicate = r.u8() / 1275.0;
          link.jitter = r.u8() * 0.0004;
          net_.client(w).up = link;
          net_.client(w).down = link;
          break;
        }
        case kCut:
          net_.cut(w);
          break;
        case kRestart:
          net_.reconnect(w, settingsOf(who));
          break;
        case kForge: {
          const std::uint8_t which = r.u8(), where = r.u8(), x = r.u8();
          if (net_.sniffed().empty()) break;
          std::vector<std::uint8_t> d = recent(which);
          if (!d.empty()) d[where % d.size()] ^= x;
          net_.injectDatagram(std::move(d), (which & 0x80) != 0 ? stranger() : address(who));
          break;
        }
        case kReplay: {
          const std::uint8_t which = r.u8();
          if (net_.sniffed().empty()) break;
          const int from = (which & 0x80) != 0 ? (who + 1) % kParticipants : who;
          net_.injectDatagram(recent(which), address(from));
          break;
        }
        case kGarbage: {
          std::vector<std::uint8_t> d(r.u8());
          for (auto& b : d) b = r.u8();
          net_.injectDatagram(std::move(d), address(who));
          break;
        }
        case kStall:
          advance((r.u8() + 1) * 0.05, false);
          break;
      }
      checkMembers();
    }
  }

  // Clean links, everyone with a session, two seconds of traffic: all live and complete.
  void settle() {
    for (int i = 0; i < kParticipants; ++i) {
      const auto w = static_cast<std::size_t>(i);
      net_.client(w).up = test::SimLink{};
      net_.client(w).down = test::SimLink{};
    }
    advance(1.0, true);  // what was in flight lands; dead sessions notice
    for (int i = 0; i < kParticipants; ++i) {
      const auto w = static_cast<std::size_t>(i);
      if (net_.session(w).state() != net::SessionState::kLive) net_.reconnect(w, settingsOf(i));
    }
    advance(1.0, true);
    std::array<std::uint64_t, kParticipants> before{};
    for (int i = 0; i < kParticipants; ++i) before[static_cast<std::size_t>(i)] = received(i);
    advance(1.0, true);
    for (int i = 0; i < kParticipants; ++i) {
      const auto w = static_cast<std::size_t>(i);
      if (net_.session(w).state() != net::SessionState::kLive) {
        std::fprintf(stderr, "participant %d: %s\n", i, net_.session(w).error().c_str());
      }
      check(net_.session(w).state() == net::SessionState::kLive,
            "after the faults end every participant is live again");
      int others = 0;
      for (const auto& m : net_.session(w).members()) {
        if (!m->is_self) ++others;
      }
      check(others == kParticipants - 1, "every participant sees the others, and no ghosts");
      check(received(i) > before[w], "every participant receives the others' postures");
    }
  }

 private:
  // One of the last kSeen datagrams the participants sent (by the low 7 bits of `which`).
  std::vector<std::uint8_t> recent(std::uint8_t which) const {
    const auto& all = net_.sniffed();
    const std::size_t n = std::min(all.size(), kSeen);
    return all[all.size() - n + (which & 0x7F) % n].bytes;
  }

  wire::Endpoint address(int i) { return net_.client(static_cast<std::size_t>(i)).endpoint; }
  static wire::Endpoint stranger() { return wire::Endpoint::ipv4(0x7F000063u, 50999); }

  void advance(double seconds, bool send) {
    net_.advance(seconds, kStep, [&](double now) {
      if (!send || now + 1e-9 < next_send_) return;
      next_send_ = now + kSendEvery;
      for (int i = 0; i < kParticipants; ++i) {
        const auto w = static_cast<std::size_t>(i);
        if (net_.session(w).state() == net::SessionState::kLive) {
          net_.session(w).sendPosture(test::syntheticPosture(now), net_.localTime(w));
        }
      }
    });
  }

  std::uint64_t received(int i) {
    std::uint64_t n = 0;
    for (const auto& [name, m] : net_.session(static_cast<std::size_t>(i)).stats().members) {
      n += m.postures_received;
    }
    return n;
  }

  void checkMembers() {
    check(net_.server().lobby().memberCount() <= kParticipants,
          "forged and replayed datagrams make no member");
  }

  test::SimNetwork net_;
  double next_send_ = 0.0;
};

// ---- seeds --------------------------------------------------------------------------

std::vector<std::uint8_t> script(std::initializer_list<std::uint8_t> ops) { return ops; }
std::uint8_t op(Op kind, int who) { return static_cast<std::uint8_t>(kind | (who << 3)); }

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  seeds.push_back({"gen_calm.bin", script({op(kAdvance, 0), 200, op(kAdvance, 0), 100})});
  seeds.push_back({"gen_lossy.bin", script({op(kLink, 0), 51, 12, 125, op(kLink, 1), 102, 0, 250,
                                            op(kAdvance, 0), 255, op(kAdvance, 0), 255})});
  seeds.push_back({"gen_cut_restart.bin",
                   script({op(kAdvance, 0), 100, op(kCut, 1), op(kAdvance, 0), 60, op(kRestart, 1),
                           op(kAdvance, 0), 120, op(kRestart, 2), op(kAdvance, 0), 120})});
  seeds.push_back({"gen_forge_replay.bin", script({op(kAdvance, 0),
                                                   120,
                                                   op(kForge, 0),
                                                   3,
                                                   1,
                                                   0x80,
                                                   op(kForge, 1),
                                                   0x85,
                                                   20,
                                                   1,
                                                   op(kReplay, 2),
                                                   5,
                                                   op(kReplay, 0),
                                                   0x86,
                                                   op(kGarbage, 1),
                                                   6,
                                                   3,
                                                   0,
                                                   0,
                                                   0,
                                                   1,
                                                   2,
                                                   op(kAdvance, 0),
                                                   80,
                                                   op(kStall, 1),
                                                   40,
                                                   op(kAdvance, 0),
                                                   100})});
  return seeds;
}

}  // namespace
}  // namespace vistel

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  spdlog::set_level(spdlog::level::off);
  vistel::fuzz::writeSeedsIfAsked(*argc, *argv, vistel::makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vistel::Run run;
  run.script(std::span(data, size));
  run.settle();
  return 0;
}
