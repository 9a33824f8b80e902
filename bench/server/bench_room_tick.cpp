// bench_room_tick: one room of the session server at 16, 50 and 100 members (issue 19:
// "tick p99 <= 2 ms at 100 members"), each member with the default avatar (its implicit
// model: the room's collision world) at the default seats, playing the gesture clips at
// 60 Hz, one ball in the room. Per iteration: one tick period of work as the server's
// room strand does it, split into
//   BM_RoomTick/M:     the tick alone (world step: pose, ball, Step 1, world datagrams),
//   BM_RoomForward/M:  every member's posture accepted and forwarded (one period),
// and reports per member-tick. Needs the build's data folder (default.vavatar and the
// gesture clips, written by the build).
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include "client/net/clip_player.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/motion/bvh.hpp"
#include "common/scene/seat_layout.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/packets.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/room.hpp"

namespace vistel::server {
namespace {

constexpr double kTick = 1.0 / 60.0;

struct Fixture {
  std::shared_ptr<const CollisionModel> model;
  int joints = 0;
  std::vector<std::unique_ptr<net::ClipPlayer>> players;  // one per clip
};

const Fixture* fixture() {
  static const std::unique_ptr<Fixture> f = []() -> std::unique_ptr<Fixture> {
    const std::string data = VISTEL_BUILD_DATA_DIR;
    auto bytes = readFileBytes(data + "/default.vavatar", 1u << 30);
    if (!bytes) return nullptr;
    auto avatar = decodeAvatar(*bytes, "default.vavatar");
    if (!avatar) return nullptr;
    auto out = std::make_unique<Fixture>();
    out->joints = avatar->skeleton.jointCount();
    const Skeleton skeleton = avatar->skeleton;
    auto model = makeCollisionModel(std::move(*avatar), CollisionLimits{}, "default");
    if (!model) return nullptr;
    out->model = *model;
    for (const char* clip : {"wave", "clap", "point", "idle"}) {
      auto bvh = loadBvh(data + "/gestures/" + clip + ".bvh");
      if (!bvh) return nullptr;
      auto player = net::ClipPlayer::create(*bvh, skeleton);
      if (!player) return nullptr;
      out->players.push_back(std::move(*player));
    }
    return out;
  }();
  return f.get();
}

// The fixture is there (else the benchmark is skipped, saying why); quiet logs.
bool ready(benchmark::State& state) {
  if (fixture() == nullptr) {
    state.SkipWithError("no default.vavatar or gesture clips in the build's data folder");
    return false;
  }
  spdlog::set_level(spdlog::level::err);
  return true;
}

struct RoomRun {
  std::unique_ptr<Room> room;
  std::vector<wire::Endpoint> endpoints;
  std::vector<std::uint16_t> sequences;
  std::vector<wire::DatagramSealer> sealers;  // each member's uplink (WIRE.md §3.9)
  Posture posture;
  std::vector<std::uint8_t> datagram;
  Effects fx;
  double now = 0.0;
};

void fill(RoomRun& run, int members) {
  const Fixture& f = *fixture();
  RoomSettings settings;
  run.room = std::make_unique<Room>(RoomId{1}, "bench", settings, 0.0);
  for (int i = 0; i < members; ++i) {
    RoomCommand c;
    c.kind = RoomCommand::Kind::kAddMember;
    c.room = RoomId{1};
    c.member = MemberId{0x00010000u + static_cast<std::uint32_t>(i)};
    c.uplink_key.fill(static_cast<std::uint8_t>(7 + i));
    c.downlink_key.fill(static_cast<std::uint8_t>(100 + i));
    run.sealers.push_back(wire::DatagramSealer{c.uplink_key});
    c.seat = seatPlacement(i, SeatLayout{});
    c.joint_count = f.joints;
    c.collision = f.model;
    run.room->apply(c, 0.0);
    c.kind = RoomCommand::Kind::kBindEndpoint;
    c.endpoint = wire::Endpoint::ipv4(0x7F000001u, static_cast<std::uint16_t>(20000 + i));
    run.endpoints.push_back(c.endpoint);
    run.room->apply(c, 0.0);
  }
  RoomCommand ball;
  ball.kind = RoomCommand::Kind::kSpawnProp;
  ball.room = RoomId{1};
  ball.prop = PropId{0x00010000u};
  ball.position = {0.0f, 1.2f, 0.0f};
  run.room->apply(ball, 0.0);
  run.sequences.assign(static_cast<std::size_t>(members), 0);
}

// Every member's posture of this period, accepted and forwarded.
void postures(RoomRun& run) {
  const Fixture& f = *fixture();
  const int members = static_cast<int>(run.sequences.size());
  for (int i = 0; i < members; ++i) {
    net::ClipPlayer& player = *f.players[static_cast<std::size_t>(i) % f.players.size()];
    player.sample(run.now + 0.37 * i, true, run.posture);
    wire::PosturePacket p;
    p.header = {0x00010000u + static_cast<std::uint32_t>(i), 0};
    wire::encodePostureRecord(run.posture, ++run.sequences[static_cast<std::size_t>(i)], run.now,
                              p.record);
    run.datagram.clear();
    wire::write(p, run.datagram);
    run.sealers[static_cast<std::size_t>(i)].seal(wire::kClientHeaderBytes, run.datagram);
    const double at = run.now + kTick * i / members;
    run.room->onDatagram(run.datagram, run.endpoints[static_cast<std::size_t>(i)], at, run.fx);
    run.room->update(at, run.fx);
  }
}

void BM_RoomTick(benchmark::State& state) {
  if (!ready(state)) return;
  const int members = static_cast<int>(state.range(0));
  RoomRun run;
  fill(run, members);
  std::vector<double> times;
  for (auto _ : state) {
    state.PauseTiming();
    postures(run);
    run.fx.clear();
    run.now += kTick;
    state.ResumeTiming();
    const auto start = std::chrono::steady_clock::now();
    run.room->update(run.room->nextTickTime(), run.fx);
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    benchmark::DoNotOptimize(run.fx.datagrams.size());
    state.PauseTiming();
    run.fx.clear();
    state.ResumeTiming();
  }
  std::sort(times.begin(), times.end());
  const auto at = [&](double q) {
    return times.empty() ? 0.0 : times[static_cast<std::size_t>(q * (times.size() - 1))];
  };
  state.counters["tick_p50_ms"] = at(0.5);
  state.counters["tick_p99_ms"] = at(0.99);
  state.counters["pairs"] = static_cast<double>(run.room->world().interactions().pairs.size());
  double sum = 0.0;
  for (double t : times) sum += t;
  state.counters["us_per_member_tick"] =
      times.empty() ? 0.0 : 1e3 * sum / static_cast<double>(times.size()) / members;
}
BENCHMARK(BM_RoomTick)->Arg(16)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);

void BM_RoomForward(benchmark::State& state) {
  if (!ready(state)) return;
  const int members = static_cast<int>(state.range(0));
  RoomRun run;
  fill(run, members);
  std::size_t datagrams = 0;
  for (auto _ : state) {
    postures(run);
    datagrams += run.fx.datagrams.size();
    state.PauseTiming();
    run.fx.clear();
    run.now += kTick;
    // Keep the tick out of this measure.
    run.room->update(run.room->nextTickTime(), run.fx);
    run.fx.clear();
    state.ResumeTiming();
  }
  state.counters["datagrams_per_period"] =
      static_cast<double>(datagrams) / static_cast<double>(state.iterations());
  state.counters["entries_per_member_period"] =
      static_cast<double>(run.room->entriesForwarded()) /
      static_cast<double>(state.iterations() * static_cast<std::uint64_t>(members));
}
BENCHMARK(BM_RoomForward)->Arg(16)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vistel::server

BENCHMARK_MAIN();
