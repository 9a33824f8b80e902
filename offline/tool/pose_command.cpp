// vistel-avatar pose FILE (--bvh CLIP --frame K | --rest) [--skinning lbs|dqs|ffd|slerp]
// --out OUT.glb: the avatar posed (rest, or a BVH frame retargeted onto it) and skinned,
// written as a rigged glTF 2.0 binary whose bind posture is that posture. ffd takes the
// spine chain below the head joint of the joint map that fits the avatar (by name when
// none fits) and falls back to dqs, with a warning on stderr, when there is none.
#include <memory>

#include <fmt/format.h>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/skinning_rig.hpp"
#include "common/glb/gltf_export.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct PoseOptions {
  std::string file;
  std::string bvh;
  int frame = -1;
  bool rest = false;
  std::string skinning = "lbs";
  std::string out;
  std::string config = "config";
};

// The BVH clip's frame retargeted onto the avatar's skeleton.
Result<Posture> clipPosture(const PoseOptions& opt, const Skeleton& target) {
  Result<MotionClip> clip = loadBvh(opt.bvh);
  if (!clip) return clip.error();
  if (opt.frame < 0 || opt.frame >= clip->frame_count) {
    return fail("{}: frame {} out of range (the clip has frames 0..{})", opt.bvh, opt.frame,
                clip->frame_count - 1);
  }
  const Skeleton source = clipSkeleton(*clip);
  Posture source_posture;
  samplePosture(*clip, opt.frame, source_posture);

  Result<std::vector<JointMap>> maps = loadJointMaps(opt.config);
  if (!maps) return maps.error();
  Result<JointMapChoice> source_map = chooseJointMap(*maps, source);
  if (!source_map)
    return withContext(fmt::format("{}: no joint map fits the clip", opt.bvh), source_map.error());
  Result<JointMapChoice> target_map = chooseJointMap(*maps, target);
  if (!target_map) {
    return withContext(fmt::format("{}: no joint map fits the avatar", opt.file),
                       target_map.error());
  }
  Result<Retargeter> retargeter =
      Retargeter::forClip(*clip, source_map->map, target, target_map->map);
  if (!retargeter) return withContext("retargeting", retargeter.error());
  Posture out;
  retargeter->apply(source_posture, out);
  return out;
}

Status runPose(const PoseOptions& opt) {
  if (opt.rest == !opt.bvh.empty()) return fail("give either --rest or --bvh CLIP --frame K");
  if (!opt.bvh.empty() && opt.frame < 0) return fail("--bvh needs --frame K (0-based)");
  Result<AvatarModel> loaded = loadAvatarFile(opt.file);
  if (!loaded) return loaded.error();
  const AvatarModel& avatar = *loaded;
  const Skeleton& skel = avatar.skeleton;

  // The posture.
  Posture posture = restPosture(skel);
  if (!opt.rest) {
    Result<Posture> p = clipPosture(opt, skel);
    if (!p) return p.error();
    posture = std::move(*p);
  }
  if (posture.rotations.size() != skel.names.size() ||
      (!posture.translations.empty() && posture.translations.size() != skel.names.size())) {
    return fail("posture has {} rotations for {} joints", posture.rotations.size(),
                skel.names.size());
  }

  // The rigid component's per-mesh data (ffd: the head from the joint map when one fits).
  const SkinningMethod method = parseSkinningMethod(opt.skinning).value_or(SkinningMethod::kLinear);
  int head = -1;
  if (method == SkinningMethod::kSpineFfd) {
    if (Result<std::vector<JointMap>> maps = loadJointMaps(opt.config); maps) {
      if (Result<JointMapChoice> map = chooseJointMap(*maps, skel); map) {
        head = skel.find(map->map.jointFor("head"));
      }
    }
  }
  const SkinningRig rig = makeSkinningRig(skel, avatar.skin, method, head);
  if (!rig.warning.empty()) fmt::print(stderr, "vistel-avatar pose: warning: {}\n", rig.warning);

  // Joints, skinning matrices, skinned vertices.
  const std::size_t nj = skel.names.size();
  const std::size_t nv = avatar.skin.positions.size();
  std::vector<glm::mat4> model(nj), skin(nj);
  std::vector<DualQuat> dq(nj);
  std::vector<glm::vec3> positions(nv), normals(nv);
  poseSkeleton(skel, posture, model);
  skinningMatrices(skel, model, skin);
  RigFrame rig_frame = makeRigFrame(rig);
  skinMesh(avatar.skin, rig, skin, dq, rig_frame, positions, normals);

  // The rigged file, bind posture = this posture.
  if (Status s = writeGlb(opt.out, posedAvatarScene(avatar, model, positions, normals)); !s)
    return s;
  const std::string what =
      opt.rest ? std::string("rest posture") : fmt::format("{} frame {}", opt.bvh, opt.frame);
  fmt::print("wrote {}: {} vertices, {} triangles, {} joints; {} ({})\n", opt.out, nv,
             avatar.skin.triangleCount(), nj, what, opt.skinning);
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerPoseCommand(CLI::App& app) {
  auto opt = std::make_shared<PoseOptions>();
  CLI::App* cmd = app.add_subcommand(
      "pose",
      "Pose an avatar (rest, or a BVH frame retargeted onto it), skin it and write it as a "
      "rigged glTF 2.0 binary");
  cmd->add_option("file", opt->file, "avatar file (.glb, .gltf or .vavatar)")->required();
  CLI::Option* bvh = cmd->add_option("--bvh", opt->bvh, "BVH motion clip");
  CLI::Option* frame = cmd->add_option("--frame", opt->frame, "frame of the clip (0-based)");
  CLI::Option* rest = cmd->add_flag("--rest", opt->rest, "use the rest posture");
  cmd->add_option("--skinning", opt->skinning,
                  "skinning method: lbs (linear blend), dqs (dual quaternion), ffd (the torso "
                  "by a lattice along the spine, the rest dqs) or slerp (rigid + slerp)")
      ->check(CLI::IsMember({"lbs", "dqs", "ffd", "slerp"}))
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "output .glb file")->required();
  cmd->add_option("--config", opt->config, "config folder with skeletons/*.toml joint maps")
      ->capture_default_str();
  rest->excludes(bvh);
  rest->excludes(frame);
  bvh->needs(frame);
  frame->needs(bvh);
  setCommandAction(cmd, [opt]() { return runPose(*opt); });
}

}  // namespace vistel
