// vistel-avatar cut AVATAR --band METRES -o DIR [--format obj|ply] [--config DIR]: the
// avatar cut into limb parts with a band of faces removed at each joint (offline/parts),
// each part written as DIR/<segment>.obj (or .ply) with its texture coordinates, and
// DIR/PARTS.toml naming the parts, the joints between them and their blend radii.
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "common/base/file.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "offline/parts/avatar_cut.hpp"
#include "offline/parts/part_files.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct CutOptions {
  std::string file;
  float band = 0.03f;
  std::string out;
  std::string format = "obj";
  std::string config = "config";
};

Status runCut(const CutOptions& opt) {
  Result<AvatarModel> avatar = loadAvatarFile(opt.file);
  if (!avatar) return avatar.error();
  Result<std::vector<JointMap>> maps = loadJointMaps(opt.config);
  if (!maps) return maps.error();
  Result<JointMapChoice> map = chooseJointMap(*maps, avatar->skeleton);
  if (!map) return withContext(opt.file, map.error());
  Result<AvatarCut> cut = cutAvatar(*avatar, map->map, opt.band);
  if (!cut) return withContext(opt.file, cut.error());

  std::error_code ec;
  std::filesystem::create_directories(opt.out, ec);
  if (ec) return fail("{}: cannot create the folder: {}", opt.out, ec.message());
  for (const CutPart& part : cut->parts) {
    const std::string path = opt.out + "/" + part.segment + "." + opt.format;
    if (Status st = writePartMesh(path, part); !st) return st;
  }
  const std::string toml = partsToml(*cut, opt.file, opt.band, opt.format);
  if (Status st = writeFileText(opt.out + "/PARTS.toml", toml); !st) return st;
  fmt::print("cut {} into {} parts at {} joints ({} triangles removed in {} m bands): {}/\n",
             opt.file, cut->parts.size(), cut->joints.size(), cut->removed_triangles, opt.band,
             opt.out);
  for (const CutPart& part : cut->parts) {
    fmt::print("  {:<11} {:>6} vertices {:>6} triangles\n", part.segment,
               part.mesh.positions.size(), part.mesh.indices.size() / 3);
  }
  return {};
}

}  // namespace

void registerCutCommand(CLI::App& app) {
  auto opt = std::make_shared<CutOptions>();
  CLI::App* cmd = app.add_subcommand(
      "cut",
      "Cut an avatar into limb parts (head, torso, upper arms, forearms, hands, thighs, shins, "
      "feet), removing a band of faces around each joint; writes each part as a mesh and a "
      "PARTS.toml");
  cmd->add_option("avatar", opt->file, "avatar file (.glb, .gltf, .vrm or .vavatar)")->required();
  cmd->add_option("--band", opt->band,
                  "width of the band removed at each joint, metres (default 0.03)")
      ->check(CLI::Range(0.001f, 0.5f));
  cmd->add_option("-o,--out", opt->out, "output folder (created)")->required();
  cmd->add_option("--format", opt->format, "part mesh format: obj (default) or ply")
      ->check(CLI::IsMember({"obj", "ply"}));
  cmd->add_option("--config", opt->config,
                  "config folder whose skeletons/*.toml joint maps take precedence over the "
                  "inferred map (default: config, else the built-in copies)");
  setCommandAction(cmd, [opt]() { return runCut(*opt); });
}

}  // namespace vistel
