// bench_wire: what the posture delta codec (common/wire/posture_delta.hpp) sends per
// member-frame, against today's 235-byte Posture datagram (proto/WIRE.md §3.4: 14-byte client
// header + 221-byte record for the 52-joint humanoid); issue 19's uplink target is <= 150 B.
//
// Streams, all at 60 Hz on the default avatar (offline/synth, 52 canonical joints):
//   (a) shared   every BVH under <shared data>/mocap (cmu, gestures) retargeted onto the avatar
//                (skipped with a message when the shared data is absent);
//   (b) gestures the bundled gesture clips (offline/gestures) retargeted onto the avatar;
//   (c) sensors  the same clips worn by the simulated rig of config/sensors/sim.toml (tracker
//                noise, "cycle" gloves) plus glove noise (1 and 2 degrees RMS per sensor),
//                calibrated and solved onto the avatar as a sim: source does, sampled every
//                other 120 Hz tick.
// Each stream goes through encoder -> channel -> decoder under several configurations
// (reference policy, keyframe interval, acknowledgement delay, loss); the table gives the mean
// datagram bytes per member-frame (14 + record), the keyframe share, frames refused for a
// missing reference, and the largest decoded rotation error against the posture sent.
// Then Google Benchmark times encode and decode per frame (items = frames).
//
// Run from the project root: build/<dir>/bench/wire/bench_wire [--benchmark_filter=...]
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/clip_solve.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/rig_simulator.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_delta.hpp"
#include "offline/gestures/gestures.hpp"
#include "offline/synth/default_avatar.hpp"

namespace vistel {
namespace {

using wire::DeltaReference;

constexpr double kRate = 60.0;
constexpr int kTodayBytes = 235;

std::string sharedData() {
  const char* env = std::getenv("VISTEL_SHARED_DATA");
  return env != nullptr && *env != '\0' ? env : VISTEL_DEFAULT_SHARED_DATA;
}

struct Stream {
  std::string group;  // "a shared", "b gestures", "c sensors"
  std::string name;
  std::vector<Posture> frames;  // 60 Hz, avatar joints
};

struct World {
  AvatarModel avatar;
  std::vector<JointMap> maps;
  const JointMap* avatar_map = nullptr;
  JointRoles avatar_roles{};
  SensorSetup setup;
};

// The clip sampled at 60 Hz and retargeted onto the avatar.
Result<std::vector<Posture>> retargetClip(const World& w, const MotionClip& clip) {
  const Skeleton skeleton = clipSkeleton(clip);
  Result<const JointMap*> clip_map = selectJointMap(w.maps, skeleton);
  if (!clip_map) return clip_map.error();
  Result<Retargeter> r = Retargeter::forClip(clip, **clip_map, w.avatar.skeleton, *w.avatar_map);
  if (!r) return r.error();
  std::vector<Posture> out;
  Posture src;
  const double duration = (clip.frame_count - 1) * clip.frame_time;
  for (int k = 0; k / kRate <= duration; ++k) {
    samplePostureAt(clip, k / kRate, src);
    Posture p;
    r->apply(src, p);
    p.time = k / kRate;
    out.push_back(std::move(p));
  }
  return out;
}

// The clip worn by the simulated rig (glove noise added), calibrated on its hold and solved onto
// the avatar: what openPostureSource("sim:CLIP") gives, sampled at 60 Hz.
Result<std::vector<Posture>> solveOnAvatar(const World& w, const MotionClip& clip,
                                           float glove_noise_deg) {
  Result<ClipBody> body = makeClipBody(clip, w.maps);
  if (!body) return body.error();
  // The calibration posture: the clip's first frame on the avatar.
  Result<const JointMap*> clip_map = selectJointMap(w.maps, body->skeleton);
  if (!clip_map) return clip_map.error();
  Result<Retargeter> r =
      Retargeter::create(body->skeleton, **clip_map, w.avatar.skeleton, *w.avatar_map);
  if (!r) return r.error();
  Posture first, calibration_posture;
  samplePosture(body->clip, 0, first);
  r->apply(first, calibration_posture);
  // The rig.
  SimOptions sim = w.setup.sim;
  sim.glove_noise_deg = glove_noise_deg;
  const MotionClip* c = &body->clip;
  const double duration = (c->frame_count - 1) * c->frame_time;
  Result<std::unique_ptr<RigSimulator>> rig = RigSimulator::create(
      body->skeleton, body->roles, [c](double t, Posture& out) { samplePostureAt(*c, t, out); },
      duration, sim);
  if (!rig) return rig.error();
  // Calibrate on the end of the hold, then solve every tick; keep one per 1/60 s.
  const double window = std::min(w.setup.calibration.window_s, sim.hold_s);
  std::vector<SensorFrame> calibration;
  std::optional<PostureSolver> solver;
  std::vector<Posture> out;
  SensorFrame frame;
  Posture solved;
  double next_emit = 0.0;
  while ((*rig)->poll(0.0, frame).isFrame()) {
    if (!solver) {
      if (frame.time >= sim.hold_s - window) calibration.push_back(frame);
      if (frame.time < sim.hold_s) continue;
      Result<BodyCalibration> cal = calibrateBody(
          w.avatar.skeleton, w.avatar_roles, calibration_posture, calibration, w.setup.calibration);
      if (!cal) return cal.error();
      Result<PostureSolver> s =
          PostureSolver::create(w.avatar.skeleton, w.avatar_roles, *cal, w.setup.solver);
      if (!s) return s.error();
      solver.emplace(std::move(*s));
    }
    solver->solve(frame, solved);
    const double t = frame.time - sim.hold_s;
    if (t + 1e-9 >= next_emit) {
      solved.time = t;
      out.push_back(solved);
      next_emit += 1.0 / kRate;
    }
  }
  return out;
}

std::vector<Stream>& streams() {
  static std::vector<Stream> all;
  return all;
}

bool prepare() {
  World w;
  Result<AvatarModel> avatar = makeDefaultAvatar();
  if (!avatar) {
    fmt::print(stderr, "bench_wire: default avatar: {}\n", avatar.error().message);
    return false;
  }
  w.avatar = std::move(*avatar);
  Result<std::vector<JointMap>> maps = loadJointMaps();
  Result<SensorSetup> setup = loadSensorSetup("config/sensors/sim.toml");
  if (!maps || !setup) {
    fmt::print(stderr, "bench_wire: {}\n", !maps ? maps.error().message : setup.error().message);
    return false;
  }
  w.maps = std::move(*maps);
  w.setup = std::move(*setup);
  Result<const JointMap*> avatar_map = selectJointMap(w.maps, w.avatar.skeleton);
  if (!avatar_map) {
    fmt::print(stderr, "bench_wire: avatar joint map: {}\n", avatar_map.error().message);
    return false;
  }
  w.avatar_map = *avatar_map;
  Result<JointRoles> roles = resolveJointRoles(w.avatar.skeleton, w.avatar_map);
  if (!roles) {
    fmt::print(stderr, "bench_wire: avatar roles: {}\n", roles.error().message);
    return false;
  }
  w.avatar_roles = *roles;

  // The clips: shared BVHs (when present) and the bundled gestures.
  std::vector<MotionClip> shared_clips;
  const std::filesystem::path mocap = std::filesystem::path(sharedData()) / "mocap";
  if (std::filesystem::is_directory(mocap)) {
    std::vector<std::string> paths;
    for (const auto& e : std::filesystem::recursive_directory_iterator(mocap)) {
      if (e.path().extension() == ".bvh") paths.push_back(e.path().string());
    }
    std::sort(paths.begin(), paths.end());
    for (const std::string& p : paths) {
      Result<MotionClip> clip = loadBvh(p);
      if (!clip) {
        fmt::print(stderr, "bench_wire: skipping {}: {}\n", p, clip.error().message);
        continue;
      }
      clip->source = std::filesystem::path(p).parent_path().filename().string() + "/" +
                     std::filesystem::path(p).stem().string();
      shared_clips.push_back(std::move(*clip));
    }
  } else {
    fmt::print("bench_wire: no shared data at {} (set VISTEL_SHARED_DATA): source (a) skipped\n",
               mocap.string());
  }
  const std::vector<MotionClip> gestures = makeBundledGestures();

  const auto add = [&](const std::string& group, const std::string& name,
                       Result<std::vector<Posture>> frames) {
    if (!frames) {
      fmt::print(stderr, "bench_wire: skipping {} {}: {}\n", group, name, frames.error().message);
      return;
    }
    streams().push_back({group, name, std::move(*frames)});
  };
  for (const MotionClip& c : shared_clips) add("a shared", c.source, retargetClip(w, c));
  for (const MotionClip& c : gestures) add("b gestures", c.source, retargetClip(w, c));
  for (float noise : {1.0f, 2.0f}) {
    const std::string suffix = fmt::format(" glove {:.0f}deg", noise);
    for (const MotionClip& c : gestures)
      add("c sensors", c.source + suffix, solveOnAvatar(w, c, noise));
    for (const MotionClip& c : shared_clips)
      add("c sensors", c.source + suffix, solveOnAvatar(w, c, noise));
  }
  return !streams().empty();
}

// ----- the codec over a channel -----

struct Config {
  const char* name;
  DeltaReference reference = DeltaReference::kAcked;
  double key_interval_s = 0.5;
  int ack_delay = 2;  // frames from sending a frame to its acknowledgement reaching the sender
  double loss = 0.0;  // both directions; with loss, the uplink also reorders (0..2 frames)
  float tolerance_deg = 0.2f;
};

struct Tally {
  long frames = 0, bytes = 0, keyframes = 0, lost = 0, refused = 0, decoded = 0;
  double max_err_deg = 0.0, max_root_mm = 0.0;
  void add(const Tally& o) {
    frames += o.frames;
    bytes += o.bytes;
    keyframes += o.keyframes;
    lost += o.lost;
    refused += o.refused;
    decoded += o.decoded;
    max_err_deg = std::max(max_err_deg, o.max_err_deg);
    max_root_mm = std::max(max_root_mm, o.max_root_mm);
  }
};

double angleDeg(const glm::quat& a, const glm::quat& b) {
  const double d =
      std::fabs(double(a.w) * b.w + double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z);
  return 2.0 * std::acos(std::min(1.0, d)) * 180.0 / 3.14159265358979;
}

Tally runStream(const std::vector<Posture>& frames, const Config& c, std::uint64_t seed) {
  wire::PostureDeltaOptions options;
  options.joint_count = static_cast<int>(frames.front().rotations.size());
  options.reference = c.reference;
  options.key_interval_s = c.key_interval_s;
  options.joint_tolerance_rad = c.tolerance_deg * 3.14159265f / 180.0f;
  if (c.tolerance_deg == 0.0f) options.root_tolerance_m = 0.0f;
  wire::PostureDeltaEncoder enc(options);
  wire::PostureDeltaDecoder dec(options.joint_count);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  struct Flight {
    long due;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Flight> up;
  std::vector<std::pair<long, std::uint16_t>> acks;
  Tally t;
  std::vector<std::uint8_t> bytes;
  wire::PostureRecord got;
  const double start = 1000.0;
  for (long i = 0; i < static_cast<long>(frames.size()); ++i) {
    // Acknowledgements due now reach the sender.
    for (auto it = acks.begin(); it != acks.end();) {
      if (it->first <= i) {
        enc.acknowledge(it->second);
        it = acks.erase(it);
      } else {
        ++it;
      }
    }
    // Send.
    const auto seq = static_cast<std::uint16_t>(i);
    bytes.clear();
    wire::DeltaFrameInfo info;
    enc.encode(frames[static_cast<std::size_t>(i)], seq, start + static_cast<double>(i) / kRate,
               false, bytes, &info);
    ++t.frames;
    t.bytes += static_cast<long>(wire::kClientHeaderBytes + bytes.size());
    t.keyframes += info.keyframe ? 1 : 0;
    if (c.loss > 0.0 && u(rng) < c.loss) {
      ++t.lost;
    } else {
      const long jitter = c.loss > 0.0 ? static_cast<long>(u(rng) * 3.0) : 0;
      up.push_back({i + jitter, bytes});
    }
    // Receive (due ones in random order), decode, acknowledge.
    std::shuffle(up.begin(), up.end(), rng);
    for (auto it = up.begin(); it != up.end();) {
      if (it->due > i) {
        ++it;
        continue;
      }
      const wire::DeltaDecodeResult r = dec.decode(it->bytes, got);
      it = up.erase(it);
      if (!r.ok()) {
        if (r.status == wire::DeltaStatus::kMissingReference) ++t.refused;
        continue;
      }
      ++t.decoded;
      const Posture& sent = frames[static_cast<std::size_t>(r.sequence)];
      for (std::size_t j = 0; j < sent.rotations.size(); ++j) {
        t.max_err_deg = std::max(t.max_err_deg,
                                 angleDeg(wire::unpackQuat(got.rotations[j]), sent.rotations[j]));
      }
      for (int k = 0; k < 3; ++k) {
        t.max_root_mm =
            std::max(t.max_root_mm, std::fabs(got.root_mm[static_cast<std::size_t>(k)] -
                                              1000.0 * double(sent.root_translation[k])));
      }
      if (c.loss > 0.0 && u(rng) < c.loss) continue;  // the acknowledgement is lost
      acks.emplace_back(i + std::max(1, c.ack_delay), r.sequence);
    }
  }
  return t;
}

// Where the bits of the delta frames go (default configuration, no loss), and what two other
// joint codings would cost on the same steps: per-component Exp-Golomb (order k) in place of
// the class + shared width, and the class coded at its entropy (an ideal adaptive code).
void printBitBudget(const std::string& group) {
  std::array<long, 8> class_count{};
  long deltas = 0, joints = 0, changed = 0, step_bits = 0, raw = 0, total_bits = 0;
  std::array<long, 4> golomb{};  // k = 0..3
  for (const Stream& s : streams()) {
    if (s.group != group) continue;
    wire::PostureDeltaOptions options;
    options.joint_count = static_cast<int>(s.frames.front().rotations.size());
    wire::PostureDeltaEncoder enc(options);
    std::vector<wire::PostureRecord> sent(s.frames.size());
    std::vector<std::uint8_t> bytes;
    for (std::size_t i = 0; i < s.frames.size(); ++i) {
      if (i >= 2) enc.acknowledge(static_cast<std::uint16_t>(i - 2));
      bytes.clear();
      wire::DeltaFrameInfo info;
      enc.encode(s.frames[i], static_cast<std::uint16_t>(i),
                 1000.0 + static_cast<double>(i) / kRate, false, bytes, &info);
      sent[i] = enc.lastReconstructed();
      if (info.keyframe) continue;
      ++deltas;
      total_bits += static_cast<long>(bytes.size()) * 8;
      const wire::PostureRecord& ref = sent[info.reference];
      for (std::size_t j = 0; j < static_cast<std::size_t>(options.joint_count); ++j) {
        ++joints;
        const std::uint32_t c = sent[i].rotations[j], r = ref.rotations[j];
        if (c == r) continue;
        ++changed;
        if ((c & 3u) != (r & 3u)) {
          ++raw;
          ++class_count[7];
          continue;
        }
        std::array<int, 3> st{};
        int m = 0;
        for (int k = 0; k < 3; ++k) {
          st[k] = static_cast<int>((c >> (2 + 10 * k)) & 1023u) -
                  static_cast<int>((r >> (2 + 10 * k)) & 1023u);
          m = std::max(m, std::max(st[k], -st[k] - 1));
        }
        int cls = 0;
        const int widths[7] = {2, 3, 4, 5, 6, 7, 9};
        while (cls < 7 && m >= (1 << (widths[cls] - 1))) ++cls;
        ++class_count[static_cast<std::size_t>(cls)];
        if (cls < 7) step_bits += 3 * widths[cls];
        for (int k = 0; k < 4; ++k) {
          for (int v : st) {
            const unsigned z =
                v >= 0 ? 2u * static_cast<unsigned>(v) : 2u * static_cast<unsigned>(-v) - 1u;
            const unsigned q = (z >> k) + 1u;
            golomb[static_cast<std::size_t>(k)] += 2 * (31 - std::countl_zero(q)) + 1 + k;
          }
        }
      }
    }
  }
  if (deltas == 0) return;
  double entropy = 0.0;
  for (long n : class_count) {
    if (n > 0) {
      const double p = static_cast<double>(n) / static_cast<double>(changed);
      entropy -= p * std::log2(p);
    }
  }
  const double d = static_cast<double>(deltas);
  fmt::print("  bit budget of a delta frame ({:.0f} bits = {:.1f} B on average):\n",
             static_cast<double>(total_bits) / d, static_cast<double>(total_bits) / d / 8.0);
  fmt::print(
      "    changed joints {:.1f} of {:.0f}; mask {:.0f} bits, classes {:.0f}, steps {:.0f}, "
      "raw {:.0f}\n",
      static_cast<double>(changed) / d, static_cast<double>(joints) / d,
      static_cast<double>(joints) / d, 3.0 * static_cast<double>(changed) / d,
      static_cast<double>(step_bits) / d, 32.0 * static_cast<double>(raw) / d);
  fmt::print(
      "    classes (widths 2,3,4,5,6,7,9,raw): {} {} {} {} {} {} {} {}; entropy {:.2f} bits\n",
      class_count[0], class_count[1], class_count[2], class_count[3], class_count[4],
      class_count[5], class_count[6], class_count[7], entropy);
  fmt::print(
      "    alternative steps, per-component Exp-Golomb k=0..3 (no class): {:.0f} {:.0f} "
      "{:.0f} {:.0f} bits; class at its entropy would save {:.0f} bits\n",
      static_cast<double>(golomb[0]) / d, static_cast<double>(golomb[1]) / d,
      static_cast<double>(golomb[2]) / d, static_cast<double>(golomb[3]) / d,
      (3.0 - entropy) * static_cast<double>(changed) / d);
}

// The downlink: the server decodes the sender's uplink (acknowledged after 2 frames, no loss)
// and re-encodes each frame for one recipient against the sender's history
// (appendForwardedPosture); the recipient loses `loss` of them and acknowledges what it decodes,
// `ack_delay` frames later. Per snapshot entry: 4-byte member id + 2-byte length + record
// (today: 4 + 221 = 225 B).
struct Forwarded {
  long frames = 0, bytes = 0, keyframes = 0, refused = 0;
};

Forwarded forwardStream(const std::vector<Posture>& frames, int ack_delay, double loss,
                        std::uint64_t seed) {
  wire::PostureDeltaOptions options;
  options.joint_count = static_cast<int>(frames.front().rotations.size());
  wire::PostureDeltaEncoder sender(options);
  wire::PostureDeltaDecoder uplink(options.joint_count), recipient(options.joint_count);
  wire::DeltaForwardState state;
  wire::PostureRecord record, scratch, got;
  std::vector<std::uint8_t> up, down;
  std::vector<std::pair<long, std::uint16_t>> acks;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Forwarded f;
  for (long i = 0; i < static_cast<long>(frames.size()); ++i) {
    const auto seq = static_cast<std::uint16_t>(i);
    if (i >= 2) sender.acknowledge(static_cast<std::uint16_t>(i - 2));
    for (auto it = acks.begin(); it != acks.end();) {
      if (it->first <= i) {
        state.acknowledge(it->second);
        it = acks.erase(it);
      } else {
        ++it;
      }
    }
    up.clear();
    sender.encode(frames[static_cast<std::size_t>(i)], seq, 1000.0 + static_cast<double>(i) / kRate,
                  false, up);
    if (!uplink.decode(up, record).ok()) continue;
    down.clear();
    wire::appendForwardedPosture(uplink, record, options, state, scratch, down);
    ++f.frames;
    f.bytes += static_cast<long>(wire::kSnapshotEntryOverhead + 2 + down.size());
    f.keyframes += down[0] & 1;
    if (u(rng) < loss) continue;
    const wire::DeltaDecodeResult r = recipient.decode(down, got);
    if (!r.ok()) {
      ++f.refused;
      continue;
    }
    acks.emplace_back(i + ack_delay, r.sequence);
  }
  return f;
}

void printDownlink(const std::string& group) {
  fmt::print(
      "  downlink, one recipient (snapshot entry = 4 B id + 2 B length + record; today 225 B):\n");
  for (const auto& [delay, loss] :
       std::vector<std::pair<int, double>>{{2, 0.0}, {6, 0.0}, {2, 0.1}}) {
    Forwarded all;
    std::uint64_t seed = 7;
    for (const Stream& s : streams()) {
      if (s.group != group) continue;
      const Forwarded f = forwardStream(s.frames, delay, loss, seed++);
      all.frames += f.frames;
      all.bytes += f.bytes;
      all.keyframes += f.keyframes;
      all.refused += f.refused;
    }
    fmt::print(
        "    ack {} frames, {:>3.0f}% loss: {:>6.1f} B per entry, keys {:.1f}%, refused {}\n",
        delay, 100.0 * loss, static_cast<double>(all.bytes) / static_cast<double>(all.frames),
        100.0 * static_cast<double>(all.keyframes) / static_cast<double>(all.frames), all.refused);
  }
}

void printTables() {
  const std::vector<Config> configs = {
      {"acked, ack 2 frames, key 0.5 s", DeltaReference::kAcked, 0.5, 2, 0.0, 0.2f},
      {"acked, ack 6 frames, key 0.5 s", DeltaReference::kAcked, 0.5, 6, 0.0, 0.2f},
      {"acked, ack 2 frames, key 0.25 s", DeltaReference::kAcked, 0.25, 2, 0.0, 0.2f},
      {"acked, ack 2, 10% loss+reorder", DeltaReference::kAcked, 0.5, 2, 0.10, 0.2f},
      {"acked, ack 6, 10% loss+reorder", DeltaReference::kAcked, 0.5, 6, 0.10, 0.2f},
      {"acked, ack 2, exact (tol 0)", DeltaReference::kAcked, 0.5, 2, 0.0, 0.0f},
      {"keyframe ref, key 0.5 s", DeltaReference::kKeyframe, 0.5, 2, 0.0, 0.2f},
      {"keyframe ref, key 0.25 s", DeltaReference::kKeyframe, 0.25, 2, 0.0, 0.2f},
      {"keyframe ref, 10% loss+reorder", DeltaReference::kKeyframe, 0.5, 2, 0.10, 0.2f},
      {"previous frame (chain), no loss", DeltaReference::kPrevious, 0.5, 2, 0.0, 0.2f},
      {"previous frame, 10% loss+reorder", DeltaReference::kPrevious, 0.5, 2, 0.10, 0.2f},
  };
  std::vector<std::string> groups;
  for (const Stream& s : streams()) {
    if (std::find(groups.begin(), groups.end(), s.group) == groups.end()) groups.push_back(s.group);
  }
  fmt::print(
      "\nBytes per member-frame (datagram: 14-byte client header + record), 60 Hz, 52 joints.\n"
      "Today: {} B every frame. Target (issue 19): <= 150 B on average.\n",
      kTodayBytes);
  for (const std::string& g : groups) {
    long frames = 0;
    int count = 0;
    for (const Stream& s : streams()) {
      if (s.group == g) {
        frames += static_cast<long>(s.frames.size());
        ++count;
      }
    }
    fmt::print("\n({}) {} streams, {} frames ({:.1f} s)\n", g, count, frames,
               static_cast<double>(frames) / kRate);
    fmt::print("  {:<34} {:>8} {:>7} {:>6} {:>8} {:>8} {:>9} {:>8}\n", "configuration", "B/frame",
               "vs 235", "keys%", "lost", "refused", "max err", "root mm");
    for (const Config& c : configs) {
      Tally all;
      std::uint64_t seed = 1;
      for (const Stream& s : streams()) {
        if (s.group == g) all.add(runStream(s.frames, c, seed++));
      }
      fmt::print(
          "  {:<34} {:>8.1f} {:>6.0f}% {:>6.1f} {:>8} {:>8} {:>8.3f}° {:>8.2f}\n", c.name,
          static_cast<double>(all.bytes) / static_cast<double>(all.frames),
          100.0 * static_cast<double>(all.bytes) / (static_cast<double>(all.frames) * kTodayBytes),
          100.0 * static_cast<double>(all.keyframes) / static_cast<double>(all.frames), all.lost,
          all.refused, all.max_err_deg, all.max_root_mm);
    }
    printBitBudget(g);
    printDownlink(g);
    // Per stream, the default configuration.
    fmt::print("  per stream ({}):\n", configs[0].name);
    std::uint64_t seed = 1;
    for (const Stream& s : streams()) {
      if (s.group != g) continue;
      const Tally t = runStream(s.frames, configs[0], seed++);
      fmt::print("    {:<32} {:>6} frames {:>8.1f} B/frame\n", s.name, t.frames,
                 static_cast<double>(t.bytes) / static_cast<double>(t.frames));
    }
  }
  fmt::print("\n");
}

// ----- timings -----

const Stream* timedStream() {
  for (const Stream& s : streams()) {
    if (s.group == "c sensors") return &s;
  }
  return streams().empty() ? nullptr : &streams().front();
}

void BM_Encode(benchmark::State& state) {
  const Stream* s = timedStream();
  wire::PostureDeltaOptions options;
  wire::PostureDeltaEncoder enc(options);
  std::vector<std::uint8_t> bytes;
  bytes.reserve(wire::kMaxDatagramBytes);
  std::uint16_t seq = 0;
  std::size_t k = 0;
  for (auto _ : state) {
    bytes.clear();
    enc.encode(s->frames[k], seq, seq / kRate, false, bytes);
    enc.acknowledge(static_cast<std::uint16_t>(seq - 2));
    benchmark::DoNotOptimize(bytes.data());
    ++seq;
    k = (k + 1) % s->frames.size();
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Decode(benchmark::State& state) {
  const Stream* s = timedStream();
  wire::PostureDeltaEncoder enc;
  std::vector<std::vector<std::uint8_t>> datagrams;
  for (std::size_t i = 0; i < s->frames.size(); ++i) {
    std::vector<std::uint8_t> b;
    const auto seq = static_cast<std::uint16_t>(i);
    enc.encode(s->frames[i], seq, static_cast<double>(i) / kRate, i == 0, b);
    if (i >= 2) enc.acknowledge(static_cast<std::uint16_t>(i - 2));
    datagrams.push_back(std::move(b));
  }
  wire::PostureDeltaDecoder dec;
  wire::PostureRecord out;
  std::size_t k = 0;
  for (auto _ : state) {
    if (k == 0) dec.reset();
    const wire::DeltaDecodeResult r = dec.decode(datagrams[k], out);
    benchmark::DoNotOptimize(r);
    k = (k + 1) % datagrams.size();
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_Encode);
BENCHMARK(BM_Decode);

}  // namespace
}  // namespace vistel

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (!vistel::prepare()) return 1;
  vistel::printTables();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
