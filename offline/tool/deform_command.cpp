// vistel-avatar deform AVATAR (--bvh CLIP [--frames A:B] [--every N] | --rest [--frames A:B])
//   [--ball X,Y,Z,R[,VX,VY,VZ]] [--ball-stiffness K] [--ball-physics] [--rigid-only]
//   [--skinning lbs|dqs|ffd|slerp] [--threads N] --out OUT.glb [--forces-csv F]
//
// Runs the avatar (and optionally a ball, a second body) through a clip frame by frame with
// the rigid and deformable components (common/scene DeformScene) and writes every frame
// into one glTF 2.0 binary as a vertex animation (morph targets, STEP-interpolated), so any
// glTF viewer plays it. --rigid-only writes the same frames without the deformable step.
// --forces-csv writes one row per body per frame: contact area and reaction force.
//
// AVATAR: a .vavatar with an implicit model, or any avatar file without one (a .glb, the
// default avatar): the model is then built on the fly with the default primitive map.
// Spaces: the avatar's model space is the world (metres, +Y up); the ball is given in it.
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/base/file.hpp"
#include "common/deform/prop.hpp"
#include "common/glb/gltf_export.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "common/scene/deform_scene.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

constexpr double kRestFrameTime = 1.0 / 30.0;  // --rest: seconds per frame

struct DeformCommandOptions {
  std::string avatar;
  std::string bvh;
  bool rest = false;
  std::string frames;  // "A:B"
  int every = 1;
  std::string ball;  // "X,Y,Z,R[,VX,VY,VZ]"
  std::string ball_origin = "world";
  std::string ball_stiffness = "rigid";
  bool ball_physics = false;
  bool rigid_only = false;
  std::string skinning = "dqs";
  int threads = 1;
  std::string out;
  std::string forces_csv;
  std::string primitives = "config/avatars/humanoid.toml";
  std::string config = "config";
  double max_mib = 256.0;  // refuse an estimated output beyond this (MiB) unless allow_large
  bool allow_large = false;
  bool quiet = false;  // no progress lines
};

struct BallArgs {
  glm::vec3 position{0.0f};
  float radius = 0.1f;
  glm::vec3 velocity{0.0f};
};

// A finite number, the whole of `text`.
bool parseNumber(std::string_view text, float& out) {
  while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
  while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size() && !text.empty() &&
         std::isfinite(out);
}

bool parseInt(std::string_view text, long long& out) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size() && !text.empty();
}

Result<BallArgs> parseBall(const std::string& text) {
  std::vector<float> v;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string_view item =
        std::string_view(text).substr(start, comma == std::string::npos ? comma : comma - start);
    float x = 0.0f;
    if (!parseNumber(item, x)) {
      return fail(
          "--ball {}: '{}' is not a finite number (expected X,Y,Z,R[,VX,VY,VZ] in metres "
          "and m/s)",
          text, item);
    }
    v.push_back(x);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (v.size() != 4 && v.size() != 7) {
    return fail("--ball {}: {} numbers; expected 4 (X,Y,Z,R) or 7 (X,Y,Z,R,VX,VY,VZ)", text,
                v.size());
  }
  BallArgs b;
  b.position = glm::vec3(v[0], v[1], v[2]);
  b.radius = v[3];
  if (!(b.radius >= 0.005f && b.radius <= 5.0f)) {
    return fail("--ball {}: radius {} m out of range (0.005 .. 5)", text, b.radius);
  }
  if (v.size() == 7) b.velocity = glm::vec3(v[4], v[5], v[6]);
  return b;
}

// "A:B" -> [A, B): first frame and end (exclusive).
Result<std::pair<int, int>> parseFrames(const std::string& text, int frame_count,
                                        const std::string& what) {
  const std::size_t colon = text.find(':');
  long long a = 0, b = 0;
  if (colon == std::string::npos || !parseInt(std::string_view(text).substr(0, colon), a) ||
      !parseInt(std::string_view(text).substr(colon + 1), b)) {
    return fail("--frames {}: expected A:B (frames A to B-1, 0-based)", text);
  }
  if (a < 0 || b <= a) {
    return fail("--frames {}: need 0 <= A < B (frames A to B-1, 0-based)", text);
  }
  if (frame_count > 0 && b > frame_count) {
    return fail("--frames {}: {} has frames 0..{} (B may be at most {})", text, what,
                frame_count - 1, frame_count);
  }
  if (b > std::numeric_limits<int>::max()) return fail("--frames {}: too large", text);
  return std::make_pair(static_cast<int>(a), static_cast<int>(b));
}

// The body's row of the forces CSV: frame, time, body, area, force, |force|, partner, and
// the force the ball's dynamics put on it over the step from this frame (|N|; empty without
// --ball-physics).
void csvRow(std::string& csv, int frame, double time, const std::string& body,
            const BodyContactSummary& s, const std::string& partner,
            const std::optional<double>& dynamics) {
  csv += fmt::format("{},{:.6f},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", frame, time, body,
                     s.area, s.force.x, s.force.y, s.force.z, glm::length(s.force), partner,
                     dynamics ? fmt::format("{:.9g}", *dynamics) : std::string());
}

std::string csvName(std::string name) {
  for (char& c : name) {
    if (c == ',' || c == '\n' || c == '\r' || c == '"') c = '_';
  }
  return name.empty() ? std::string("body") : name;
}

Status runDeform(const DeformCommandOptions& opt) {
  if (opt.rest == !opt.bvh.empty()) return fail("give either --bvh CLIP or --rest");
  if (opt.every < 1) return fail("--every {}: must be >= 1", opt.every);
  if (opt.threads < 1 || opt.threads > 64) return fail("--threads {}: 1 .. 64", opt.threads);

  // Ball arguments first (cheap to check).
  std::optional<BallArgs> ball_args;
  if (!opt.ball.empty()) {
    Result<BallArgs> b = parseBall(opt.ball);
    if (!b) return b.error();
    ball_args = *b;
  }
  float ball_stiffness = kRigidStiffness;
  if (opt.ball_stiffness != "rigid") {
    if (!parseNumber(opt.ball_stiffness, ball_stiffness) || !(ball_stiffness > 0.0f)) {
      return fail("--ball-stiffness {}: expected 'rigid' or a positive number (Pa per metre)",
                  opt.ball_stiffness);
    }
  }
  if (opt.ball_physics && !ball_args) return fail("--ball-physics needs --ball");

  // The clip and the frame range.
  std::optional<MotionClip> clip;
  int first = 0, end = 1;
  double frame_time = kRestFrameTime;
  if (!opt.bvh.empty()) {
    Result<MotionClip> loaded = loadBvh(opt.bvh);
    if (!loaded) return loaded.error();
    clip = std::move(*loaded);
    end = clip->frame_count;
    frame_time = clip->frame_time;
  }
  if (!opt.frames.empty()) {
    Result<std::pair<int, int>> range =
        parseFrames(opt.frames, clip ? clip->frame_count : 0, clip ? opt.bvh : "--rest");
    if (!range) return range.error();
    std::tie(first, end) = *range;
  }
  const int frame_count = (end - first + opt.every - 1) / opt.every;
  if (static_cast<std::size_t>(frame_count) > kMaxGltfFrames) {
    return fail(
        "{} frames to export; one glTF file holds at most {} (use --frames A:B or --every N)",
        frame_count, kMaxGltfFrames);
  }

  // The avatar, with an implicit model (built here when the file has none).
  Result<AvatarModel> loaded = loadAvatarFile(opt.avatar);
  if (!loaded) return loaded.error();
  auto avatar = std::make_shared<AvatarModel>(std::move(*loaded));
  const bool needs_model = !opt.rigid_only || opt.ball_physics;
  if (!avatar->implicit && needs_model) {
    fmt::print(stderr,
               "{} has no implicit model: building one with {} (save it with `vistel-avatar "
               "build` to skip this)\n",
               opt.avatar, opt.primitives);
    std::string last_stage;
    Status built = buildAvatarImplicit(
        *avatar, opt.primitives, opt.config, [&last_stage](float f, std::string_view stage) {
          if (stage == last_stage) return;
          last_stage = std::string(stage);
          fmt::print(stderr, "build: {:3.0f}% {}\n", 100.0f * f, stage);
        });
    if (!built) return built;
  }

  // Retargeting the clip onto the avatar; the avatar's hips.
  std::optional<Retargeter> retargeter;
  Posture clip_posture;
  Result<std::vector<JointMap>> maps = loadJointMaps(opt.config);
  if (!maps) return maps.error();
  int hips = 0;
  if (Result<JointMapChoice> map = chooseJointMap(*maps, avatar->skeleton); map) {
    hips = std::max(0, avatar->skeleton.find(map->map.jointFor("hips")));
  }
  if (clip) {
    const Skeleton clip_skeleton = clipSkeleton(*clip);
    Result<JointMapChoice> clip_map = chooseJointMap(*maps, clip_skeleton);
    if (!clip_map) {
      return withContext(fmt::format("{}: no joint map fits the clip", opt.bvh), clip_map.error());
    }
    Result<JointMapChoice> avatar_map = chooseJointMap(*maps, avatar->skeleton);
    if (!avatar_map) {
      return withContext(fmt::format("{}: no joint map fits the avatar", opt.avatar),
                         avatar_map.error());
    }
    Result<Retargeter> r =
        Retargeter::forClip(*clip, clip_map->map, avatar->skeleton, avatar_map->map);
    if (!r) return withContext("retargeting", r.error());
    retargeter = std::move(*r);
  }

  // The first frame's posture and where the hips are then.
  Posture first_posture = restPosture(avatar->skeleton);
  if (retargeter) {
    samplePosture(*clip, first, clip_posture);
    retargeter->apply(clip_posture, first_posture);
  }
  std::vector<glm::mat4> first_joints(static_cast<std::size_t>(avatar->skeleton.jointCount()));
  poseSkeleton(avatar->skeleton, first_posture, first_joints);
  const glm::vec3 first_hips(first_joints[static_cast<std::size_t>(hips)][3]);
  if (ball_args && opt.ball_origin == "hips") ball_args->position += first_hips;

  // The scene: the avatar, and the ball as a second body.
  std::vector<SceneBody> bodies;
  const std::string avatar_name = csvName(avatar->name.empty() ? "avatar" : avatar->name);
  bodies.push_back(SceneBody{avatar_name, avatar, glm::mat4(1.0f), true});
  BallState ball_state;
  BallStepOptions ball_step;
  if (ball_args) {
    BallSpec spec;
    spec.radius = ball_args->radius;
    spec.stiffness = ball_stiffness;
    Result<std::shared_ptr<const AvatarModel>> ball = makeBallAvatar(spec, "ball");
    if (!ball) return withContext("--ball", ball.error());
    bodies.push_back(
        SceneBody{"ball", *ball, glm::translate(glm::mat4(1.0f), ball_args->position), true});
    ball_state.position = ball_args->position;
    ball_state.velocity = ball_args->velocity;
    ball_state.radius = ball_args->radius;
    ball_state.stiffness = ball_stiffness;
    ball_step.skip_body = 1;
    if (Status valid = validateBallState(ball_state); !valid) {
      return withContext("--ball", valid.error());
    }
  }
  SceneOptions scene_options;
  scene_options.rigid_only = opt.rigid_only;
  scene_options.threads = opt.threads;
  scene_options.skinning =
      parseSkinningMethod(opt.skinning).value_or(SkinningMethod::kDualQuaternion);
  Result<DeformScene> created = DeformScene::create(std::move(bodies), scene_options);
  if (!created) return created.error();
  DeformScene& scene = *created;
  if (const std::string& why = scene.skinningRig(0).warning; !why.empty()) {
    fmt::print(stderr, "vistel-avatar deform: warning: {}\n", why);
  }
  const int nbody = scene.bodyCount();

  // The exported mesh: the avatar's skin, then the ball's (one mesh; vertex offsets).
  GltfScene gltf;
  gltf.frame_time = frame_time * opt.every;
  gltf.mesh.name = nbody > 1 ? avatar_name + "+ball" : avatar_name;
  std::vector<std::size_t> vertex_offset(static_cast<std::size_t>(nbody) + 1, 0);
  for (int i = 0; i < nbody; ++i) {
    const SkinMesh& skin = scene.body(i).avatar->skin;
    const auto offset = static_cast<std::uint32_t>(vertex_offset[static_cast<std::size_t>(i)]);
    for (std::uint32_t index : skin.indices) gltf.mesh.indices.push_back(index + offset);
    vertex_offset[static_cast<std::size_t>(i) + 1] = offset + skin.positions.size();
  }
  const std::size_t total_vertices = vertex_offset.back();
  // The file holds a morph target (positions and normals, float32) per frame beside the
  // mesh, and the animation's one-hot weights (frames^2 floats) and times: estimate it
  // before spending the time, and refuse what nobody can open.
  const auto frames_d = static_cast<double>(frame_count);
  const double estimate_mib =
      ((frames_d + 1.0) * static_cast<double>(total_vertices) * 24.0 +
       static_cast<double>(gltf.mesh.indices.size()) * 4.0 + frames_d * (frames_d + 1.0) * 4.0) /
      (1024.0 * 1024.0);
  if (estimate_mib > opt.max_mib && !opt.allow_large) {
    return fail(
        "{}: about {:.0f} MiB for {} frames of {} vertices, over --max-size {:.0f} MiB (fewer "
        "frames with --frames A:B or --every N, or --allow-large to write it anyway)",
        opt.out, estimate_mib, frame_count, total_vertices, opt.max_mib);
  }
  if (!opt.quiet) {
    fmt::print(stderr, "vistel-avatar deform: {} frames of {} vertices, about {:.1f} MiB\n",
               frame_count, total_vertices, estimate_mib);
  }
  gltf.frames.reserve(static_cast<std::size_t>(frame_count));

  // Frame by frame.
  std::string csv =
      "frame,time_s,body,contact_area_m2,force_x_n,force_y_n,force_z_n,force_n,partner,"
      "dynamics_force_n\n";
  SceneTimings total;
  double step_ms = 0.0;
  std::int64_t iterations = 0, iterating = 0, unsolved = 0, held = 0, smoothed = 0;
  int contact_frames = 0;
  double max_force = 0.0, max_area = 0.0;
  const double t0 = first * frame_time;
  std::vector<glm::vec3> dynamics_on(static_cast<std::size_t>(nbody));  // per frame: N
  auto last_progress = std::chrono::steady_clock::now();
  for (int k = 0; k < frame_count; ++k) {
    if (!opt.quiet && k > 0 &&
        std::chrono::steady_clock::now() - last_progress > std::chrono::seconds(2)) {
      last_progress = std::chrono::steady_clock::now();
      fmt::print(stderr, "vistel-avatar deform: frame {} of {} ({:.0f}%)\n", k, frame_count,
                 100.0 * k / frame_count);
    }
    const int frame = first + k * opt.every;
    const double time = frame * frame_time;
    if (retargeter) {
      samplePosture(*clip, frame, clip_posture);
      retargeter->apply(clip_posture, scene.posture(0));
    }
    if (ball_args && !opt.ball_physics) {
      const glm::vec3 p = ball_args->position + ball_args->velocity * static_cast<float>(time - t0);
      scene.setPlacement(1, glm::translate(glm::mat4(1.0f), p));
    } else if (ball_args) {
      scene.setPlacement(1, ballPlacement(ball_state));
    }
    const auto start = std::chrono::steady_clock::now();
    if (Status st = scene.step(time); !st)
      return withContext(fmt::format("frame {}", frame), st.error());
    step_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const SceneTimings& t = scene.timings();
    total.skin_ms += t.skin_ms;
    total.pose_ms += t.pose_ms;
    total.step1_ms += t.step1_ms;
    total.deform_ms += t.deform_ms;

    // The ball's next position under its dynamics (gravity, floor, the avatar's primitives),
    // from the configuration of this frame: the forces they put on each body.
    std::fill(dynamics_on.begin(), dynamics_on.end(), glm::vec3(0.0f));
    if (ball_args && opt.ball_physics) {
      const BallStepReport report =
          stepBall(ball_state, scene.bodyViews(), static_cast<float>(gltf.frame_time), ball_step);
      for (int c = 0; c < report.contact_count; ++c) {
        const BallContact& bc = report.contacts[static_cast<std::size_t>(c)];
        if (bc.body < 0 || bc.body >= nbody) continue;               // the floor
        dynamics_on[static_cast<std::size_t>(bc.body)] -= bc.force;  // reaction on the body
        dynamics_on[1] += bc.force;                                  // on the ball
      }
    }

    // The frame's vertices (world = the avatar's model space).
    GltfFrame& out = gltf.frames.emplace_back();
    out.positions.resize(total_vertices);
    out.normals.resize(total_vertices);
    bool contact = false;
    for (int i = 0; i < nbody; ++i) {
      const std::span<const glm::vec3> p = scene.positions(i);
      const std::span<const glm::vec3> n = scene.normals(i);
      std::copy(p.begin(), p.end(),
                out.positions.begin() +
                    static_cast<std::ptrdiff_t>(vertex_offset[static_cast<std::size_t>(i)]));
      std::copy(n.begin(), n.end(),
                out.normals.begin() +
                    static_cast<std::ptrdiff_t>(vertex_offset[static_cast<std::size_t>(i)]));
      const BodyContactSummary s = scene.contactSummary(i);
      std::string partner;
      if (s.partner >= 0) {
        partner = scene.body(s.partner).name;
      } else if (s.self_area > 0.0) {
        partner = "self";
      }
      std::optional<double> dynamics;
      if (ball_args && opt.ball_physics)
        dynamics = glm::length(dynamics_on[static_cast<std::size_t>(i)]);
      csvRow(csv, frame, time, scene.body(i).name, s, partner, dynamics);
      contact = contact || s.area > 0.0;
      max_force = std::max(max_force, glm::length(s.force));
      max_area = std::max(max_area, s.area);
      if (const DeformState* state = scene.deformState(i)) {
        iterations += state->counters.iterations;
        iterating += state->counters.iterating_vertices;
        unsolved += state->counters.unsolved_vertices;
        held += state->counters.held_vertices;
        smoothed += state->counters.smoothed_vertices;
      }
    }
    if (contact) ++contact_frames;
  }
  gltf.mesh.positions = gltf.frames.front().positions;
  gltf.mesh.normals = gltf.frames.front().normals;
  if (gltf.frames.size() == 1) gltf.frames.clear();  // a still: no animation

  // Files.
  if (Status st = writeGlb(opt.out, gltf); !st) return st;
  if (!opt.forces_csv.empty()) {
    if (Status st = writeFileText(opt.forces_csv, csv); !st) return st;
  }

  // Summary.
  const double nf = frame_count;
  const std::string source = clip ? fmt::format("{} frames {}..{} every {}", opt.bvh, first,
                                                first + (frame_count - 1) * opt.every, opt.every)
                                  : fmt::format("rest posture, {} frames", frame_count);
  fmt::print("deform: {} ({} vertices{}){}; {}; {}\n", avatar_name, avatar->skin.vertexCount(),
             avatar->implicit
                 ? fmt::format(", {} primitives", avatar->implicit->primitives.items.size())
                 : std::string(),
             nbody > 1 ? fmt::format(" + ball r={} m", ball_args->radius) : std::string(), source,
             opt.rigid_only ? "rigid only" : "rigid + deformable");
  const double deform_per_frame = total.deform_ms / nf;
  fmt::print(
      "per frame (mean of {}, {} thread{}): skinning {:.3f} ms, posing {:.3f} ms, step 1 {:.3f} "
      "ms, steps 2-3 {:.3f} ms ({:.1f} M vertices/s), whole frame {:.3f} ms\n",
      frame_count, opt.threads, opt.threads > 1 ? "s" : "", total.skin_ms / nf, total.pose_ms / nf,
      total.step1_ms / nf, deform_per_frame,
      deform_per_frame > 0.0 ? static_cast<double>(total_vertices) / (deform_per_frame * 1e3) : 0.0,
      step_ms / nf);
  fmt::print("first frame: hips '{}' at ({:.3f}, {:.3f}, {:.3f}) m{}\n",
             avatar->skeleton.names[static_cast<std::size_t>(hips)], first_hips.x, first_hips.y,
             first_hips.z,
             ball_args ? fmt::format("; ball at ({:.3f}, {:.3f}, {:.3f}) m", ball_args->position.x,
                                     ball_args->position.y, ball_args->position.z)
                       : std::string());
  if (!opt.rigid_only) {
    fmt::print(
        "contact in {} of {} frames; largest contact area {:.6f} m^2, largest |F| {:.4g} N; "
        "iterations per iterating vertex {:.2f}; unsolved vertex-frames {}, held {}, smoothed {}\n",
        contact_frames, frame_count, max_area, max_force,
        iterating > 0 ? static_cast<double>(iterations) / static_cast<double>(iterating) : 0.0,
        unsolved, held, smoothed);
  }
  fmt::print("wrote {}: {} frames at {:.4g} s, {} vertices, {} triangles\n", opt.out, frame_count,
             gltf.frame_time, total_vertices, gltf.mesh.indices.size() / 3);
  if (!opt.forces_csv.empty()) {
    fmt::print("wrote {}: {} rows\n", opt.forces_csv, frame_count * nbody);
  }
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerDeformCommand(CLI::App& app) {
  auto opt = std::make_shared<DeformCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "deform",
      "Animate an avatar (a BVH clip retargeted onto it, or its rest posture) with the "
      "deformable component, optionally with a ball, into one glTF 2.0 binary");
  cmd->add_option("avatar", opt->avatar,
                  "avatar file (.vavatar with an implicit model; a .glb/.gltf or a .vavatar "
                  "without one gets it built on the fly)")
      ->required();
  CLI::Option* bvh = cmd->add_option("--bvh", opt->bvh, "BVH motion clip");
  CLI::Option* rest = cmd->add_flag("--rest", opt->rest, "hold the rest posture");
  cmd->add_option("--frames", opt->frames,
                  "A:B = frames A to B-1 (0-based; default: the whole clip, or 0:1 with --rest)");
  cmd->add_option("--every", opt->every, "export every Nth frame of the range")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--ball", opt->ball,
                  "a ball X,Y,Z,R[,VX,VY,VZ] (centre and radius in metres in the avatar's "
                  "model space at the first frame, velocity in m/s: a straight line)");
  cmd->add_option("--ball-origin", opt->ball_origin,
                  "what --ball's X,Y,Z are relative to: world (the avatar's model space) or hips "
                  "(the avatar's hips at the first frame, world axes)")
      ->check(CLI::IsMember({"world", "hips"}))
      ->capture_default_str();
  cmd->add_option("--ball-stiffness", opt->ball_stiffness, "'rigid' or Pa per metre of penetration")
      ->capture_default_str();
  cmd->add_flag("--ball-physics", opt->ball_physics,
                "move the ball by its dynamics (gravity, a floor at y = 0, bouncing off the "
                "avatar's primitives) instead of a straight line");
  cmd->add_flag("--rigid-only", opt->rigid_only,
                "skinning only: the same frames without the deformable component");
  cmd->add_option("--skinning", opt->skinning,
                  "lbs (linear blend), dqs (dual quaternion), ffd (the torso by a lattice along "
                  "the spine, the rest dqs) or slerp (rigid + slerp)")
      ->check(CLI::IsMember({"lbs", "dqs", "ffd", "slerp"}))
      ->capture_default_str();
  cmd->add_option("--threads", opt->threads, "threads for skinning and steps 2-3")
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "output .glb file")->required();
  cmd->add_option("--forces-csv", opt->forces_csv,
                  "write contact area and reaction force per body per frame (CSV)");
  cmd->add_option("--primitives", opt->primitives,
                  "primitive map for an avatar without an implicit model")
      ->capture_default_str();
  cmd->add_option("--config", opt->config, "config folder with skeletons/*.toml joint maps")
      ->capture_default_str();
  cmd->add_option("--max-size", opt->max_mib,
                  "refuse when the output would exceed this many MiB (estimated before any "
                  "frame is computed)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--allow-large", opt->allow_large, "write the file whatever its size");
  cmd->add_flag("--quiet", opt->quiet, "no size estimate or progress lines on stderr");
  rest->excludes(bvh);
  setCommandAction(cmd, [opt]() { return runDeform(*opt); });
}

}  // namespace vistel
