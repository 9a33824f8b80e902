#include "server/web/avatar_glb.hpp"

#include "common/anim/skin_mesh.hpp"
#include "common/glb/gltf_export.hpp"

namespace vistel::server {

Result<std::vector<std::uint8_t>> avatarGlb(const AvatarModel& avatar) {
  if (Status st = validateAvatar(avatar); !st) return st.error();
  if (avatar.skin.indices.empty() || avatar.skin.positions.empty()) {
    return fail("avatar '{}' has no triangles", avatar.name);
  }
  GltfScene scene = restAvatarScene(avatar);
  scene.generator = "vistel-server";
  if (scene.mesh.normals.size() != scene.mesh.positions.size()) {
    scene.mesh.normals.assign(scene.mesh.positions.size(), glm::vec3(0.0f));
    computeVertexNormals(scene.mesh.positions, scene.mesh.indices, scene.mesh.normals);
  }
  keepLargestInfluences(*scene.skin, 4);  // three.js skins with JOINTS_0/WEIGHTS_0 alone
  auto glb = encodeGlb(scene);
  if (!glb) return fail("avatar '{}': {}", avatar.name, glb.error().message);
  return glb;
}

}  // namespace vistel::server
