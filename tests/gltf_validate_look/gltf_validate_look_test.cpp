// Exported avatars with their look (texture coordinates, materials, PNG textures, normal
// maps, several primitives) pass the Khronos glTF validator with 0 errors.
#include <gtest/gtest.h>

#include "common/glb/gltf_export.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/gltf/gltf_look_models.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

void expectValid(const GltfScene& scene, const std::string& name) {
  const std::string path = test::scratchDir() + "/" + name;
  ASSERT_TRUE(writeGlb(path, scene).ok());
  VISTEL_VALIDATE_OR_SKIP(verdict, path);
  EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
}

TEST(GltfValidateLook, TexturedBoxWithTwoMaterialsAndANormalMap) {
  GltfScene scene = test::texturedBoxScene(
      test::makePng(16, 16, [](int x, int y) { return glm::u8vec4(16 * x, 16 * y, 128, 255); }),
      glm::vec4(0.9f, 0.8f, 0.7f, 1.0f));
  AvatarTexture normal;
  normal.name = "bumps";
  normal.mime = "image/png";
  normal.encoded = test::makePng(8, 8, [](int, int) { return glm::u8vec4(128, 128, 255, 255); });
  normal.width = normal.height = 8;
  scene.look.textures.push_back(normal);
  AvatarMaterial cap;
  cap.name = "cap";
  cap.normal_texture = 1;
  cap.alpha_mode = AlphaMode::kMask;
  cap.double_sided = true;
  scene.look.materials.push_back(cap);
  scene.look.submeshes = {{0, 24, 0}, {24, 12, 1}};
  expectValid(scene, "look_box.glb");
}

TEST(GltfValidateLook, DefaultAvatarWithItsTexture) {
  DefaultAvatarOptions options;
  options.target_vertices = 4000;
  Result<AvatarModel> avatar = makeDefaultAvatar(options);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  ASSERT_EQ(avatar->look.textures.size(), 1u);
  expectValid(restAvatarScene(*avatar), "look_default.glb");
}

TEST(GltfValidateLook, ImportedTexturedAvatarReexported) {
  auto glb = encodeGlb(test::texturedBoxScene(
      test::makePng(4, 4, [](int x, int) { return glm::u8vec4(60 * x, 20, 200, 255); })));
  ASSERT_TRUE(glb.ok());
  auto avatar = importGltfAvatarFromMemory(*glb, "box.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  expectValid(restAvatarScene(*avatar), "look_reexported.glb");
}

}  // namespace
}  // namespace vistel
