// vistel-avatar info FILE [--json] [--config DIR]: counts, joints, influences and bounds of an
// avatar, and the joint map chosen for it (a config/skeletons map, or an inferred one).
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/motion/auto_joint_map.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct InfoOptions {
  std::string file;
  bool json = false;
  std::string config = "config";
};

// The joint map chosen for the skeleton, or why none is.
Result<JointMapChoice> chosenMap(const Skeleton& skeleton, const std::string& config) {
  Result<std::vector<JointMap>> maps = loadJointMaps(config);
  if (!maps) return maps.error();
  return chooseJointMap(*maps, skeleton);
}

Status runInfo(const InfoOptions& opt) {
  std::vector<std::string> warnings;
  Result<AvatarModel> loaded = loadAvatarFile(opt.file, &warnings);
  if (!loaded) return loaded.error();
  const AvatarModel& avatar = *loaded;
  const Skeleton& skel = avatar.skeleton;
  const SkinMesh& skin = avatar.skin;
  const Bounds box = computeBounds(skin.positions);
  const glm::vec3 size = box.max - box.min;
  const Result<JointMapChoice> map = chosenMap(skel, opt.config);

  // One JSON object on stdout.
  if (opt.json) {
    nlohmann::json out = {{"file", opt.file},
                          {"name", avatar.name},
                          {"vertices", skin.vertexCount()},
                          {"triangles", skin.triangleCount()},
                          {"joints", skel.names},
                          {"parents", skel.parents},
                          {"max_influences", maxInfluencesUsed(skin)},
                          {"influence_slots", skin.influences},
                          {"bbox_min", {box.min.x, box.min.y, box.min.z}},
                          {"bbox_max", {box.max.x, box.max.y, box.max.z}},
                          {"size", {size.x, size.y, size.z}},
                          {"warnings", warnings},
                          {"look",
                           {{"materials", avatar.look.materials.size()},
                            {"textures", avatar.look.textures.size()},
                            {"texture_bytes", avatar.look.textureBytes()},
                            {"texture_coordinates", !avatar.look.uvs.empty()}}}};
    if (map) {
      nlohmann::json joints = nlohmann::json::object();
      for (std::size_t i = 0; i < map->map.canonical.size(); ++i) {
        joints[map->map.canonical[i]] = {{"joint", map->map.joint[i]}, {"from", map->origin[i]}};
      }
      out["joint_map"] = {{"name", map->map.name},
                          {"inferred", map->inferred},
                          {"joints", joints},
                          {"notes", map->notes}};
    } else {
      out["joint_map"] = {{"error", map.error().message}};
    }
    std::cout << out.dump() << std::endl;
    return {};
  }

  // Text: a summary, then the joints with their parents.
  fmt::print("file:            {}\n", opt.file);
  fmt::print("name:            {}\n", avatar.name);
  fmt::print("vertices:        {}\n", skin.vertexCount());
  fmt::print("triangles:       {}\n", skin.triangleCount());
  fmt::print("joints:          {}\n", skel.jointCount());
  fmt::print("max influences:  {} per vertex ({} slots)\n", maxInfluencesUsed(skin),
             skin.influences);
  fmt::print("bbox min:        {:.4f} {:.4f} {:.4f} m\n", box.min.x, box.min.y, box.min.z);
  fmt::print("bbox max:        {:.4f} {:.4f} {:.4f} m\n", box.max.x, box.max.y, box.max.z);
  fmt::print("size:            {:.4f} x {:.4f} x {:.4f} m\n", size.x, size.y, size.z);
  fmt::print("look:            {} materials, {} textures ({} bytes){}\n",
             avatar.look.materials.size(), avatar.look.textures.size(), avatar.look.textureBytes(),
             avatar.look.uvs.empty() ? "" : ", texture coordinates");
  for (const AvatarTexture& t : avatar.look.textures) {
    fmt::print("  texture '{}': {} {}x{}, {} bytes\n", t.name, t.mime, t.width, t.height,
               t.encoded.size());
  }
  fmt::print("joint hierarchy (index name <- parent):\n");
  for (int j = 0; j < skel.jointCount(); ++j) {
    const int p = skel.parents[static_cast<std::size_t>(j)];
    fmt::print("  {:3} {} <- {}\n", j, skel.names[static_cast<std::size_t>(j)],
               p == kNoParent ? std::string("(root)") : skel.names[static_cast<std::size_t>(p)]);
  }
  // The mapping to canonical joints (a non-humanoid still gets the rest of the report).
  if (map) {
    fmt::print("joint map ({} canonical joints; canonical <- joint [from]):\n{}",
               map->map.canonical.size(), describeJointMapChoice(*map));
  } else {
    fmt::print("joint map: none: {}\n", map.error().message);
  }
  if (!warnings.empty()) {
    fmt::print("warnings:\n");
    for (const std::string& w : warnings) fmt::print("  {}\n", w);
  }
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerInfoCommand(CLI::App& app) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Print vertices, triangles, joints (names, parents), maximum influences per vertex "
      "the bounding box (metres) of an avatar (.glb, .gltf or .vavatar), and the joint map chosen "
      "for it (per canonical joint: the avatar's joint and where the match came from)");
  cmd->add_option("file", opt->file, "avatar file (.glb, .gltf or .vavatar)")->required();
  cmd->add_flag("--json", opt->json, "print one JSON object instead of text");
  cmd->add_option("--config", opt->config,
                  "config folder whose skeletons/*.toml joint maps take precedence over the "
                  "inferred map (default: config, else the built-in copies)");
  setCommandAction(cmd, [opt]() { return runInfo(*opt); });
}

}  // namespace vistel
