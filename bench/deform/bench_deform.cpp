// Benchmarks of the deformable component (issue 4): skinning (LBS, DQS, and issue 25's
// spine lattice and rigid + slerp, whose per-mesh rigs are built once outside the timed
// loop, as at load) and Steps 1-3 over the same frames and mesh, the same scene with the
// mesh subdivided 1x, 4x, 16x, and a brute-force triangle-triangle contact baseline on the
// same scene.
//
// Scene: makehuman_game_engine.glb (the default avatar when the shared data is absent)
// retargeted from 48 consecutive 30 Hz frames of the CMU clip 01_01 (12 for the scaling
// runs), with a rigid ball pressed against the chest; Steps 1-3 on one core. One iteration
// covers all the frames (the time column is per iteration; seconds_per_frame per frame).
// Each frame's rigid component (dual-quaternion skinning) runs untimed just before its
// Steps 1-3, as DeformScene::step runs them, so the deformation finds its input where the
// skinning left it and the rest of the cache as the skinning left it (skinned frames made
// in advance would have been evicted long before their turn).
// Counters: vertices_per_second (vertices deformed or skinned per second); for the
// deformation also iterations_per_vertex (mean root-finding iterations over the vertices
// that iterate), unsolved and contact vertices per frame, and where a frame's time goes
// (step1_seconds, then pass_a, pass_b, relax, smooth, normals and contacts _seconds: wall time
// per frame of Step 1 and of each phase of Steps 2-3, DeformOptions::time_phases); for the
// brute-force baseline the triangle pairs it tests and the intersections it finds per frame.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <unordered_map>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/skinning_rig.hpp"
#include "common/deform/deform.hpp"
#include "common/deform/mesh_quality.hpp"
#include "common/deform/prop.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "offline/build/build_model.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/synth/default_avatar.hpp"

namespace vistel {
namespace {

std::string sharedPath(const std::string& relative) {
  const char* env = std::getenv("VISTEL_SHARED_DATA");
  return std::string(env != nullptr ? env : VISTEL_DEFAULT_SHARED_DATA) + "/" + relative;
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

// Midpoint subdivision (each triangle into four); new vertices blend their edge's ends.
SkinMesh subdivide(const SkinMesh& m) {
  SkinMesh out = m;
  const auto k = static_cast<std::size_t>(m.influences);
  std::unordered_map<std::uint64_t, std::uint32_t> mid;
  const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
    const auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const auto i = static_cast<std::uint32_t>(out.positions.size());
    out.positions.push_back(0.5f * (out.positions[a] + out.positions[b]));
    out.normals.push_back(glm::normalize(out.normals[a] + out.normals[b]));
    // Union of both ends' influences at half weight, the k heaviest kept.
    std::map<std::uint16_t, float> w;
    for (std::size_t s = 0; s < k; ++s) {
      w[out.joints[a * k + s]] += 0.5f * out.weights[a * k + s];
      w[out.joints[b * k + s]] += 0.5f * out.weights[b * k + s];
    }
    std::vector<std::pair<float, std::uint16_t>> sorted;
    for (const auto& [j, x] : w) sorted.emplace_back(x, j);
    std::sort(sorted.rbegin(), sorted.rend());
    sorted.resize(k, {0.0f, 0});
    float sum = 0.0f;
    for (const auto& e : sorted) sum += e.first;
    for (const auto& e : sorted) {
      out.joints.push_back(e.second);
      out.weights.push_back(e.first / sum);
    }
    mid.emplace(key, i);
    return i;
  };
  out.indices.clear();
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const std::uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.indices.insert(out.indices.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
  }
  return out;
}

struct Frame {
  std::vector<glm::mat4> skin;       // skinning matrices
  std::vector<glm::vec3> rigid_pos;  // DQS-skinned positions
  std::vector<glm::vec3> rigid_nrm;
  glm::mat4 ball{1.0f};  // ball placement
};

struct Scene {
  std::string avatar_name;
  AvatarModel avatar;
  ImplicitModel model;
  PrimitiveSet ball;
  CombinationGraph ball_graph;
  std::vector<Posture> postures;
  std::vector<Frame> frames;
  std::vector<std::uint32_t> arm_faces, body_faces;  // for the triangle baseline
};

Result<AvatarModel> loadAvatar() {
  const std::string glb = sharedPath("avatars/makehuman_game_engine.glb");
  if (exists(glb)) return importGltfAvatar(glb);
  return makeDefaultAvatar();
}

// The scene at subdivision level (0, 1, 2 = 1x, 4x, 16x triangles); frames: how many.
Scene* makeScene(int level, int frame_count) {
  static std::map<std::pair<int, int>, std::unique_ptr<Scene>> cache;
  auto& slot = cache[{level, frame_count}];
  if (slot) return slot.get();
  auto s = std::make_unique<Scene>();
  Result<AvatarModel> avatar = loadAvatar();
  if (!avatar) {
    fmt::print(stderr, "bench_deform: {}\n", avatar.error().message);
    std::exit(1);
  }
  s->avatar = std::move(*avatar);
  for (int l = 0; l < level; ++l) s->avatar.skin = subdivide(s->avatar.skin);
  s->avatar_name = fmt::format("{} ({} vertices)", s->avatar.name, s->avatar.skin.vertexCount());
  Result<std::vector<JointMap>> maps = loadJointMaps();
  Result<const JointMap*> map =
      maps ? selectJointMap(*maps, s->avatar.skeleton) : Result<const JointMap*>(maps.error());
  Result<PrimitiveMapSpec> spec = loadPrimitiveMap();
  if (!map || !spec) {
    fmt::print(stderr, "bench_deform: no joint map or primitive map\n");
    std::exit(1);
  }
  Result<ImplicitModel> model = buildImplicitModel(s->avatar, *spec, *map);
  if (!model) {
    fmt::print(stderr, "bench_deform: {}\n", model.error().message);
    std::exit(1);
  }
  s->model = std::move(*model);
  BallSpec ball;
  ball.radius = 0.09f;
  s->ball = *makeBallPrimitives(ball);
  finalizeGraph(s->ball_graph, 1);

  // Postures: CMU 01_01 retargeted (rest posture when the clip is absent).
  const std::string bvh = sharedPath("mocap/cmu/01_01.bvh");
  const Skeleton& sk = s->avatar.skeleton;
  if (exists(bvh)) {
    Result<MotionClip> clip = loadBvh(bvh);
    const Skeleton cs = clipSkeleton(*clip);
    Result<const JointMap*> cmap = selectJointMap(*maps, cs);
    Result<Retargeter> rt = Retargeter::create(cs, **cmap, sk, **map);
    Posture src, dst;
    // Consecutive frames at 30 Hz from the middle of the clip (arms swinging, turning).
    const int step = std::max(1, static_cast<int>(std::lround(1.0 / (30.0 * clip->frame_time))));
    const int first = std::max(0, clip->frame_count / 2 - frame_count * step / 2);
    for (int f = 0; f < frame_count; ++f) {
      samplePosture(*clip, std::min(first + f * step, clip->frame_count - 1), src);
      rt->apply(src, dst);
      s->postures.push_back(dst);
    }
  } else {
    s->postures.assign(static_cast<std::size_t>(frame_count), restPosture(sk));
  }
  // Rigid component per frame, and a ball pressed 2 cm into the chest.
  const auto nj = static_cast<std::size_t>(sk.jointCount());
  const auto nv = s->avatar.skin.positions.size();
  std::vector<glm::mat4> model_xf(nj);
  std::vector<DualQuat> dq(nj);
  int torso = 0;
  for (std::size_t i = 0; i < s->model.primitives.items.size(); ++i) {
    if (s->model.primitives.items[i].name == "torso") torso = static_cast<int>(i);
  }
  for (const Posture& p : s->postures) {
    Frame fr;
    fr.skin.resize(nj);
    poseSkeleton(sk, p, model_xf);
    skinningMatrices(sk, model_xf, fr.skin);
    fr.rigid_pos.resize(nv);
    fr.rigid_nrm.resize(nv);
    skinMesh(s->avatar.skin, SkinningMethod::kDualQuaternion, fr.skin, dq, fr.rigid_pos,
             fr.rigid_nrm);
    const Primitive& t = s->model.primitives.items[static_cast<std::size_t>(torso)];
    const glm::mat4& bone = fr.skin[static_cast<std::size_t>(t.bone)];
    const glm::vec3 centre(bone * glm::vec4(t.shape.a, 1.0f));
    const glm::vec3 forward = glm::normalize(glm::mat3(bone) * t.shape.normal);
    fr.ball = glm::translate(glm::mat4(1.0f), centre + (t.r_in + ball.radius - 0.02f) * forward);
    s->frames.push_back(std::move(fr));
  }
  // Triangle sets for the baseline: arms (upper arms, forearms, hands) against the trunk
  // and head, by the vertices' owning primitives.
  const auto owner_name = [&](std::uint32_t v) -> const std::string& {
    static const std::string none;
    const auto& pr = s->model.calibration.prims[v];
    const int o = s->model.calibration.vertex_class[v] == VertexClass::kJoint ? pr[1] : pr[0];
    return o >= 0 ? s->model.primitives.items[static_cast<std::size_t>(o)].name : none;
  };
  const auto& ix = s->avatar.skin.indices;
  for (std::uint32_t f = 0; f < ix.size() / 3; ++f) {
    const std::string& n = owner_name(ix[3 * f]);
    if (n.find("arm") != std::string::npos || n.find("hand") != std::string::npos)
      s->arm_faces.push_back(f);
    if (n == "torso" || n == "pelvis" || n == "head" || n == "neck") s->body_faces.push_back(f);
  }
  slot = std::move(s);
  return slot.get();
}

constexpr int kFrames = 48;       // frames of the skinning and Steps 1-3 benchmarks
constexpr int kScaleFrames = 12;  // frames of the scaling benchmarks (the same at every level)

void skinBench(benchmark::State& state, SkinningMethod method) {
  Scene* s = makeScene(0, kFrames);
  const Skeleton& sk = s->avatar.skeleton;
  const auto nj = static_cast<std::size_t>(sk.jointCount());
  const auto nv = s->avatar.skin.positions.size();
  std::vector<glm::mat4> model_xf(nj), skin(nj);
  std::vector<DualQuat> dq(nj);
  std::vector<glm::vec3> pos(nv), nrm(nv);
  const bool rigged = method == SkinningMethod::kSpineFfd || method == SkinningMethod::kRigidSlerp;
  const SkinningRig rig = rigged ? makeSkinningRig(sk, s->avatar.skin, method) : SkinningRig{};
  RigFrame rig_frame = makeRigFrame(rig);
  for (auto _ : state) {
    for (const Posture& posture : s->postures) {
      poseSkeleton(sk, posture, model_xf);
      skinningMatrices(sk, model_xf, skin);
      if (rigged) {
        skinMesh(s->avatar.skin, rig, skin, dq, rig_frame, pos, nrm);
      } else {
        skinMesh(s->avatar.skin, method, skin, dq, pos, nrm);
      }
      benchmark::DoNotOptimize(pos.data());
      benchmark::ClobberMemory();
    }
  }
  const double frames = static_cast<double>(s->postures.size());
  state.counters["vertices_per_second"] = benchmark::Counter(
      static_cast<double>(nv) * frames, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["seconds_per_frame"] = benchmark::Counter(
      frames, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.SetLabel(rig.warning.empty() ? s->avatar_name : s->avatar_name + " (" + rig.warning + ")");
}

void BM_Skin_LBS(benchmark::State& state) { skinBench(state, SkinningMethod::kLinear); }
void BM_Skin_DQS(benchmark::State& state) { skinBench(state, SkinningMethod::kDualQuaternion); }
void BM_Skin_FFD(benchmark::State& state) { skinBench(state, SkinningMethod::kSpineFfd); }
void BM_Skin_Slerp(benchmark::State& state) { skinBench(state, SkinningMethod::kRigidSlerp); }

// Steps 1-3 (pose primitives, interaction list, deformation with contact); one benchmark
// iteration runs every frame of the scene in order (warm starts carry over between frames).
void deformBench(benchmark::State& state, Scene* s) {
  PosedPrimitives posed, ball_posed;
  InteractionScratch scratch;
  InteractionList list;
  DeformState ds;
  if (!initDeformState(s->model, s->avatar.skin.indices, ds).ok()) std::abort();
  std::int64_t iterations = 0, iterating = 0, unsolved = 0, held = 0, contact = 0, frames = 0;
  std::int64_t smoothed = 0;
  std::int64_t evaluations = 0, rigid = 0, candidates = 0, relaxed = 0, relax_iterations = 0;
  const double dt = 1.0 / 30.0;
  DeformOptions options;
  options.time_phases = true;  // a clock read between phases
  DeformPhaseTimes phases;     // summed over the frames
  double step1_seconds = 0.0;
  // The rigid component's output and scratch.
  const auto nv_skin = s->avatar.skin.positions.size();
  std::vector<glm::vec3> rigid_pos(nv_skin), rigid_nrm(nv_skin);
  std::vector<DualQuat> dq(s->frames.empty() ? 0 : s->frames.front().skin.size());
  for (auto _ : state) {
    for (const Frame& fr : s->frames) {
      state.PauseTiming();
      skinMesh(s->avatar.skin, SkinningMethod::kDualQuaternion, fr.skin, dq, rigid_pos, rigid_nrm);
      state.ResumeTiming();
      // Step 1.
      const auto step1_start = std::chrono::steady_clock::now();
      posePrimitives(s->model.primitives, fr.skin, posed);
      const glm::mat4 ball_xf[1] = {fr.ball};
      posePrimitives(s->ball, ball_xf, ball_posed);
      const BodyView views[2] = {{&s->model.graph, &posed}, {&s->ball_graph, &ball_posed}};
      buildInteractions(views, scratch, list);
      step1_seconds +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - step1_start).count();
      // Steps 2-3.
      DeformInput in;
      in.rigid_positions = rigid_pos;
      in.rigid_normals = rigid_nrm;
      in.indices = s->avatar.skin.indices;
      in.rest_positions = s->avatar.skin.positions;
      in.time = static_cast<double>(frames) * dt;
      deformSkin(s->model, views, 0, list, in, ds, options);
      benchmark::DoNotOptimize(ds.positions.data());
      phases += ds.counters.phase_seconds;
      iterations += ds.counters.iterations;
      iterating += ds.counters.iterating_vertices;
      unsolved += ds.counters.unsolved_vertices;
      held += ds.counters.held_vertices;
      smoothed += ds.counters.smoothed_vertices;
      contact += ds.counters.contact_vertices;
      evaluations += ds.counters.evaluations;
      rigid += ds.counters.rigid_vertices;
      candidates += ds.counters.candidate_vertices;
      relaxed += ds.counters.relaxed_vertices;
      relax_iterations += ds.counters.relax_iterations;
      ++frames;
    }
  }
  const double nv = static_cast<double>(s->avatar.skin.positions.size());
  const double per_iteration = static_cast<double>(s->frames.size());
  state.counters["vertices_per_second"] =
      benchmark::Counter(nv * per_iteration, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["seconds_per_frame"] = benchmark::Counter(
      per_iteration, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["iterations_per_vertex"] =
      iterating > 0 ? static_cast<double>(iterations) / static_cast<double>(iterating) : 0.0;
  const double nf = static_cast<double>(std::max<std::int64_t>(frames, 1));
  state.counters["unsolved_per_frame"] = static_cast<double>(unsolved) / nf;
  state.counters["held_per_frame"] = static_cast<double>(held) / nf;
  state.counters["smoothed_per_frame"] = static_cast<double>(smoothed) / nf;
  state.counters["contact_per_frame"] = static_cast<double>(contact) / nf;
  state.counters["evaluations_per_vertex"] = static_cast<double>(evaluations) / (nf * nv);
  state.counters["rigid_per_frame"] = static_cast<double>(rigid) / nf;
  state.counters["candidate_vertices_per_frame"] = static_cast<double>(candidates) / nf;
  state.counters["relaxed_per_frame"] = static_cast<double>(relaxed) / nf;
  state.counters["relax_iterations_per_frame"] = static_cast<double>(relax_iterations) / nf;
  // Where a frame's time goes (seconds per frame, wall time): Step 1, then the phases of
  // Steps 2-3 (DeformPhaseTimes).
  state.counters["step1_seconds"] = step1_seconds / nf;
  state.counters["pass_a_seconds"] = phases.penetration / nf;
  state.counters["pass_b_seconds"] = phases.solve / nf;
  state.counters["relax_seconds"] = phases.relax / nf;
  state.counters["smooth_seconds"] = phases.smooth / nf;
  state.counters["normals_seconds"] = phases.normals / nf;
  state.counters["contacts_seconds"] = phases.contacts / nf;
  state.SetLabel(s->avatar_name);
}

void BM_Deform_Steps123(benchmark::State& state) { deformBench(state, makeScene(0, kFrames)); }

int levelOf(std::int64_t n) { return n >= 16 ? 2 : (n >= 4 ? 1 : 0); }

void BM_Deform_Scale(benchmark::State& state) {
  const int level = levelOf(state.range(0));
  deformBench(state, makeScene(level, kScaleFrames));
}

// Brute force: every arm triangle against every trunk and head triangle (box test, then
// the exact triangle test), on the rigidly skinned mesh; one iteration is one frame.
void BM_TriTri_Scale(benchmark::State& state) {
  const int level = levelOf(state.range(0));
  Scene* s = makeScene(level, kScaleFrames);
  const auto& ix = s->avatar.skin.indices;
  std::vector<Bounds> arm_box(s->arm_faces.size()), body_box(s->body_faces.size());
  std::size_t f = 0;
  std::int64_t hits = 0;
  for (auto _ : state) {
    const auto& p = s->frames[f].rigid_pos;
    const auto box = [&](std::uint32_t t) {
      const glm::vec3 a = p[ix[3 * t]], b = p[ix[3 * t + 1]], c = p[ix[3 * t + 2]];
      return Bounds{glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c))};
    };
    for (std::size_t i = 0; i < arm_box.size(); ++i) arm_box[i] = box(s->arm_faces[i]);
    for (std::size_t j = 0; j < body_box.size(); ++j) body_box[j] = box(s->body_faces[j]);
    std::int64_t count = 0;
    for (std::size_t i = 0; i < arm_box.size(); ++i) {
      const Bounds& a = arm_box[i];
      for (std::size_t j = 0; j < body_box.size(); ++j) {
        const Bounds& b = body_box[j];
        if (a.max.x < b.min.x || b.max.x < a.min.x || a.max.y < b.min.y || b.max.y < a.min.y ||
            a.max.z < b.min.z || b.max.z < a.min.z) {
          continue;
        }
        const std::uint32_t ta = s->arm_faces[i], tb = s->body_faces[j];
        count += trianglesIntersect(p[ix[3 * ta]], p[ix[3 * ta + 1]], p[ix[3 * ta + 2]],
                                    p[ix[3 * tb]], p[ix[3 * tb + 1]], p[ix[3 * tb + 2]]);
      }
    }
    hits += count;
    benchmark::DoNotOptimize(count);
    f = (f + 1) % s->frames.size();
  }
  state.counters["vertices_per_second"] =
      benchmark::Counter(static_cast<double>(s->avatar.skin.positions.size()),
                         benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangle_pairs"] =
      static_cast<double>(s->arm_faces.size()) * static_cast<double>(s->body_faces.size());
  state.counters["intersections_per_frame"] =
      static_cast<double>(hits) /
      static_cast<double>(std::max<std::int64_t>(state.iterations(), 1));
  state.SetLabel(s->avatar_name);
}

BENCHMARK(BM_Skin_LBS)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Skin_DQS)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Skin_FFD)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Skin_Slerp)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform_Steps123)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform_Scale)->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TriTri_Scale)->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vistel

BENCHMARK_MAIN();
