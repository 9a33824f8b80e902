// vistel-avatar default --out OUT.glb|OUT.vavatar [--primitives MAP] [--config DIR]: the
// project's own default avatar. A .vavatar also carries its implicit model (fitted with the
// humanoid primitive map, as `vistel-avatar build` does), so clients deform it; a .glb has
// the skinned mesh only.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "common/avatar/avatar_io.hpp"
#include "common/glb/gltf_export.hpp"
#include "offline/synth/default_avatar.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct DefaultOptions {
  std::string out;
  std::string primitives = "config/avatars/humanoid.toml";
  std::string config = "config";
};

Status runDefault(const DefaultOptions& opt) {
  const std::string& out = opt.out;
  std::string ext = std::filesystem::path(out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".glb" && ext != ".vavatar") {
    return fail("{}: --out must end in .glb or .vavatar", out);
  }
  Result<AvatarModel> avatar = makeDefaultAvatar();
  if (!avatar) return withContext("default avatar", avatar.error());
  if (ext == ".vavatar") {
    if (Status built = buildAvatarImplicit(*avatar, opt.primitives, opt.config, {}); !built) {
      return withContext("default avatar", built.error());
    }
  }
  Status written =
      ext == ".glb" ? writeGlb(out, restAvatarScene(*avatar)) : saveAvatar(*avatar, out);
  if (!written) return written;
  fmt::print("wrote {}: {} vertices, {} triangles, {} joints{}\n", out, avatar->skin.vertexCount(),
             avatar->skin.triangleCount(), avatar->skeleton.jointCount(),
             avatar->implicit
                 ? fmt::format(", {} primitives", avatar->implicit->primitives.items.size())
                 : std::string());
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerDefaultCommand(CLI::App& app) {
  auto opt = std::make_shared<DefaultOptions>();
  CLI::App* cmd =
      app.add_subcommand("default", "Write the project's default avatar (.glb or .vavatar)");
  cmd->add_option("--out", opt->out, "output file, .glb or .vavatar")->required();
  cmd->add_option("--primitives", opt->primitives, "primitive map (TOML) for a .vavatar's model")
      ->capture_default_str();
  cmd->add_option("--config", opt->config, "config folder with skeletons/*.toml joint maps")
      ->capture_default_str();
  setCommandAction(cmd, [opt]() { return runDefault(*opt); });
}

}  // namespace vistel
