// bench_room: one room-frame of the site client's CPU work (issue 19, "Client" target).
//
// A seated room (common/scene/seat_layout.hpp, the default SeatLayout) of 1, 16 or 100
// default avatars (offline/synth, with the implicit model config/avatars/humanoid.toml
// builds), member i playing bundled gesture clip i % 4 (offline/gestures, retargeted onto
// the avatar) at its own phase. Member 0 is the viewer (the self member). A room-frame is
// what vistel-client does between two draws: RoomDeformer::sync and prepare (every body
// posed once, Step 1 across the room, level-of-detail tiers), RoomView::render in headless
// mode (skinning and Steps 2-3 in the view's worker pool, on every core; no GL), and
// RoomDeformer::finish (contacts). The postures are copied into the members' views before
// the clock starts (the network's part).
//
// Rooms: members:1, members:16, members:100 on the default layout (about a metre between
// neighbours: they rarely touch), and members:16/crowded, 16 members 0.5 m apart on one
// ring, shoulder to shoulder, so that Steps 2-3 work on contacts between neighbours.
//
// Modes: rigid (no deformable component), full (every body deformed every frame, the
// client before level of detail), lod (DeformLodSettings{}: near bodies and bodies in
// contact at full rate, farther ones every 3rd frame, the rest rigid), lod_gpu (lod with
// ViewOptions::gpu_skinning: the rigid bodies, and the lower-rate ones between their
// deformations, are skinned by the GPU's vertex shader, so the CPU only poses them; what
// vistel-client does by default).
//
// Counters per benchmark: p50_ms / p99_ms / max_ms of a room-frame, ms_per_avatar (mean
// frame / members), fps_p99 (1000 / p99_ms), threads, and per frame on average: full,
// reduced, rigid (bodies per tier), deformed (bodies whose Steps 2-3 ran), prepare_ms (of
// which pose_ms and step1_ms: one thread), view_ms (the view's pose, skin and deform
// batch), deform_cpu_ms (Steps 2-3 summed over threads); touching_pairs: pairs of bodies
// in contact in the last frame. Targets: p99 of the 16-member room-frame <= 12 ms on 2
// threads; the 100-member room >= 30 fps (p99 <= 33 ms) with lod. Run from the project
// root.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "client/deform/room_deformer.hpp"
#include "client/view/room_view.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "common/scene/seat_layout.hpp"
#include "offline/build/build_model.hpp"
#include "offline/gestures/gestures.hpp"
#include "offline/synth/default_avatar.hpp"

namespace vistel {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kFrameRate = 60.0;  // the client's frame rate (config/client.toml)

enum class Mode { kRigid = 0, kFull = 1, kLod = 2, kLodGpu = 3 };

// The default avatar with its implicit model, and every clip sampled at the frame rate.
struct RoomAssets {
  std::shared_ptr<const AvatarModel> avatar;
  std::vector<std::vector<Posture>> clips;  // per clip: one loop at kFrameRate
};

[[noreturn]] void die(const std::string& what) {
  fmt::print(stderr, "bench_room: {}\n", what);
  std::exit(1);
}

const RoomAssets& assets() {
  static const RoomAssets built = [] {
    RoomAssets a;
    Result<AvatarModel> made = makeDefaultAvatar();
    if (!made) die(made.error().message);
    auto avatar = std::make_shared<AvatarModel>(std::move(*made));
    Result<std::vector<JointMap>> maps = loadJointMaps();
    if (!maps) die(maps.error().message);
    Result<PrimitiveMapSpec> spec = loadPrimitiveMap();
    if (!spec) die(spec.error().message);
    Result<const JointMap*> map = selectJointMap(*maps, avatar->skeleton);
    if (!map) die(map.error().message);
    Result<ImplicitModel> model = buildImplicitModel(*avatar, *spec, *map);
    if (!model) die(model.error().message);
    avatar->implicit = std::move(*model);
    a.avatar = avatar;

    // The gesture clips retargeted onto the avatar, one posture per frame of the client.
    for (const MotionClip& clip : makeBundledGestures()) {
      const Skeleton clip_skeleton = clipSkeleton(clip);
      Result<const JointMap*> clip_map = selectJointMap(*maps, clip_skeleton);
      if (!clip_map) die(clip.source + ": " + clip_map.error().message);
      Result<Retargeter> retarget = Retargeter::forClip(clip, **clip_map, avatar->skeleton, **map);
      if (!retarget) die(clip.source + ": " + retarget.error().message);
      const int frames = std::max(1, static_cast<int>(std::lround(clip.duration() * kFrameRate)));
      std::vector<Posture>& out = a.clips.emplace_back(static_cast<std::size_t>(frames));
      Posture source;
      for (int f = 0; f < frames; ++f) {
        samplePostureAt(clip, f / kFrameRate, source);
        retarget->apply(source, out[static_cast<std::size_t>(f)]);
      }
    }
    if (a.clips.empty()) die("no gesture clips");
    return a;
  }();
  return built;
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (values[hi] - values[lo]) * (rank - static_cast<double>(lo));
}

void roomFrame(benchmark::State& state, int members, Mode mode, const SeatLayout& layout) {
  const RoomAssets& a = assets();
  const int threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  ViewOptions view_options;
  view_options.headless = true;
  view_options.worker_threads = threads;
  view_options.gpu_skinning = mode == Mode::kLodGpu;
  Result<std::unique_ptr<RoomView>> made = RoomView::create(view_options);
  if (!made) die(made.error().message);
  RoomView& view = **made;
  RoomDeformer deformer;
  DeformLodSettings lod;
  lod.enabled = mode == Mode::kLod || mode == Mode::kLodGpu;
  if (Status st = deformer.setLod(lod); !st) die(st.error().message);

  // The seated room; member i plays clip i % nclip from its own phase.
  std::vector<MemberView> views(static_cast<std::size_t>(members));
  std::vector<std::size_t> phase(views.size());
  for (int i = 0; i < members; ++i) {
    MemberView& v = views[static_cast<std::size_t>(i)];
    v.id = static_cast<std::uint32_t>(i + 1);
    v.name = fmt::format("member {}", i);
    v.avatar = a.avatar;
    v.placement = seatTransform(seatPlacement(i, layout));
    v.is_self = i == 0;
    phase[static_cast<std::size_t>(i)] = static_cast<std::size_t>(i) * 37;
  }
  std::int64_t frame = 0;
  auto setPostures = [&] {
    for (std::size_t i = 0; i < views.size(); ++i) {
      const std::vector<Posture>& clip = a.clips[i % a.clips.size()];
      views[i].posture = clip[(static_cast<std::size_t>(frame) + phase[i]) % clip.size()];
    }
  };
  auto runFrame = [&] {
    if (mode != Mode::kRigid) {
      if (Status st = deformer.sync(views, view); !st) die(st.error().message);
      if (Status st = deformer.prepare(static_cast<double>(frame) / kFrameRate); !st) {
        die(st.error().message);
      }
    }
    view.render(views);
    if (mode != Mode::kRigid) deformer.finish();
  };

  // Warm-up: the scene is built, buffers sized, every lower-rate body has held offsets.
  for (int w = 0; w < 2 * lod.reduced_every; ++w, ++frame) {
    setPostures();
    runFrame();
  }

  std::vector<double> ms;
  ms.reserve(static_cast<std::size_t>(state.max_iterations));
  double full = 0, reduced = 0, rigid = 0, deformed = 0, pairs = 0, prepare = 0, deform_cpu = 0;
  double pose = 0, step1 = 0, skin = 0;
  for (auto _ : state) {
    setPostures();
    const Clock::time_point start = Clock::now();
    runFrame();
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    state.SetIterationTime(seconds);
    ms.push_back(seconds * 1e3);
    if (mode != Mode::kRigid) {
      const DeformFrameStats& s = deformer.lastStats();
      full += s.full;
      reduced += s.reduced;
      rigid += s.rigid;
      deformed += s.deformed;
      prepare += s.prepare_ms;
      pose += s.pose_ms;
      step1 += s.step1_ms;
      deform_cpu += s.deform_cpu_ms;
      for (const BodyView& body : deformer.bodyViews()) benchmark::DoNotOptimize(body);
    } else {
      rigid += members;
    }
    skin += view.lastStats().skin_ms;
    ++frame;
  }
  if (mode != Mode::kRigid) {
    // Pairs between different bodies in the last frame's list (for the report).
    for (int i = 0; i < members; ++i) {
      const std::optional<BodyContactSummary> c =
          deformer.contact(static_cast<std::uint32_t>(i + 1));
      if (c) pairs += c->partner_count;
    }
    pairs /= 2;
  }
  const auto n = static_cast<double>(std::max<std::size_t>(ms.size(), 1));
  double mean = 0.0;
  for (const double m : ms) mean += m;
  mean /= n;
  const double p99 = percentile(ms, 99.0);
  state.counters["p50_ms"] = percentile(ms, 50.0);
  state.counters["p99_ms"] = p99;
  state.counters["max_ms"] = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  state.counters["ms_per_avatar"] = mean / members;
  state.counters["fps_p99"] = p99 > 0.0 ? 1000.0 / p99 : 0.0;
  state.counters["threads"] = view.workerThreads();
  state.counters["full"] = full / n;
  state.counters["reduced"] = reduced / n;
  state.counters["rigid"] = rigid / n;
  state.counters["deformed"] = deformed / n;
  state.counters["touching_pairs"] = pairs;
  state.counters["prepare_ms"] = prepare / n;
  state.counters["pose_ms"] = pose / n;
  state.counters["step1_ms"] = step1 / n;
  state.counters["view_ms"] = skin / n;
  state.counters["deform_cpu_ms"] = deform_cpu / n;
  state.SetItemsProcessed(state.iterations() * members);
}

const char* modeName(Mode mode) {
  return mode == Mode::kRigid  ? "rigid"
         : mode == Mode::kFull ? "full"
         : mode == Mode::kLod  ? "lod"
                               : "lod_gpu";
}

}  // namespace
}  // namespace vistel

int main(int argc, char** argv) {
  using vistel::Mode;
  // Frames per benchmark: enough for a p99 and well under a minute in all on 2 cores.
  // "crowded": 16 members shoulder to shoulder (0.5 m apart on one ring), so neighbours
  // touch and Steps 2-3 work on contacts (the worst case of a room).
  struct Case {
    int members;
    int frames;
    bool crowded;
  };
  vistel::SeatLayout crowded;
  crowded.first_radius_m = 1.3f;
  crowded.spacing_m = 0.5f;
  for (const Case c :
       {Case{1, 240, false}, Case{16, 120, false}, Case{16, 60, true}, Case{100, 60, false}}) {
    for (const Mode mode : {Mode::kRigid, Mode::kFull, Mode::kLod, Mode::kLodGpu}) {
      if (c.crowded && (mode == Mode::kRigid || mode == Mode::kLodGpu)) continue;
      const std::string name = fmt::format("BM_RoomFrame/members:{}{}/{}", c.members,
                                           c.crowded ? "/crowded" : "", vistel::modeName(mode));
      const vistel::SeatLayout layout = c.crowded ? crowded : vistel::SeatLayout{};
      benchmark::RegisterBenchmark(name.c_str(),
                                   [c, mode, layout](benchmark::State& state) {
                                     vistel::roomFrame(state, c.members, mode, layout);
                                   })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(c.frames);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
