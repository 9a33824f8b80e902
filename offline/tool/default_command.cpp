// vistel-avatar default --out OUT.glb|OUT.vavatar: the project's own default avatar.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "common/avatar/avatar_io.hpp"
#include "offline/gltf/gltf_export.hpp"
#include "offline/synth/default_avatar.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

Status runDefault(const std::string& out) {
  std::string ext = std::filesystem::path(out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".glb" && ext != ".vavatar") {
    return fail("{}: --out must end in .glb or .vavatar", out);
  }
  Result<AvatarModel> avatar = makeDefaultAvatar();
  if (!avatar) return withContext("default avatar", avatar.error());
  Status written =
      ext == ".glb" ? writeGlb(out, restAvatarScene(*avatar)) : saveAvatar(*avatar, out);
  if (!written) return written;
  fmt::print("wrote {}: {} vertices, {} triangles, {} joints\n", out, avatar->skin.vertexCount(),
             avatar->skin.triangleCount(), avatar->skeleton.jointCount());
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerDefaultCommand(CLI::App& app) {
  auto out = std::make_shared<std::string>();
  CLI::App* cmd =
      app.add_subcommand("default", "Write the project's default avatar (.glb or .vavatar)");
  cmd->add_option("--out", *out, "output file, .glb or .vavatar")->required();
  setCommandAction(cmd, [out]() { return runDefault(*out); });
}

}  // namespace vistel
