// An imported textured avatar on the client's renderer (RoomView, EGL offscreen): the
// pixels show its texture, textures are decoded as sRGB while factors are linear, on the
// CPU- and the GPU-skinned paths; avatars cast a shadow on the floor.
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/render/scene_renderer.hpp"
#include "client/view/room_view.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/glb/gltf_export.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/gltf/gltf_look_models.hpp"
#include "tests/render/render_checks.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// The avatar as a user gets it: a .glb exported, imported, saved and loaded as .vavatar.
std::shared_ptr<const AvatarModel> importBox(const std::vector<std::uint8_t>& png,
                                             const glm::vec4& factor = glm::vec4(1.0f)) {
  auto glb = encodeGlb(test::texturedBoxScene(png, factor));
  EXPECT_TRUE(glb.ok()) << glb.error().message;
  auto avatar = importGltfAvatarFromMemory(*glb, "box.glb");
  EXPECT_TRUE(avatar.ok()) << avatar.error().message;
  auto loaded = decodeAvatar(encodeAvatar(*avatar), "box.vavatar");
  EXPECT_TRUE(loaded.ok()) << loaded.error().message;
  return std::make_shared<const AvatarModel>(std::move(*loaded));
}

ViewOptions options(bool gpu, bool shadows = true) {
  ViewOptions o;
  o.width = 320;
  o.height = 240;
  o.offscreen = true;
  o.show_tags = false;
  o.gpu_skinning = gpu;
  o.shadows = shadows;
  o.msaa_samples = 4;
  return o;
}

MemberView memberAt(std::uint32_t id, std::shared_ptr<const AvatarModel> avatar, float x) {
  const Posture rest = restPosture(avatar->skeleton);
  return MemberView{
      id,   "", std::move(avatar), rest, glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, 0.0f)),
      false};
}

// With VISTEL_LOOK_PNG_DIR set, frames are saved there for a person to look at.
void keep(const Image& image, const std::string& name) {
  if (const char* dir = std::getenv("VISTEL_LOOK_PNG_DIR"); dir != nullptr) {
    EXPECT_TRUE(writePng(image, std::string(dir) + "/" + name + ".png").ok());
  }
}

// The pixel of a room point (must be in the frame).
glm::ivec3 pixelAt(const Image& image, const EyeCamera& eye, const glm::vec3& p) {
  int x = 0, row = 0;
  EXPECT_TRUE(test::pixelOf(eye, image.height, p, x, row));
  EXPECT_TRUE(x >= 0 && x < image.width && row >= 0 && row < image.height) << x << "," << row;
  x = std::clamp(x, 0, image.width - 1);
  row = std::clamp(row, 0, image.height - 1);
  const std::uint8_t* px = image.pixel(x, row);
  return {px[0], px[1], px[2]};
}

class RenderLook : public ::testing::TestWithParam<bool> {};

TEST_P(RenderLook, ImportedTextureShowsOnTheAvatar) {
  VISTEL_MAKE_VIEW(view, options(GetParam()));
  // Left half red, right half blue (as seen from the front, +Z).
  const auto png = test::makePng(32, 16, [](int x, int) {
    return x < 16 ? glm::u8vec4(230, 25, 20, 255) : glm::u8vec4(25, 40, 235, 255);
  });
  const MemberView m = memberAt(1, importBox(png), 0.0f);
  view->render(std::span(&m, 1));
  EXPECT_EQ(view->lastWarning(), "");
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  ASSERT_EQ(view->lastCameras().size(), 1u);
  const EyeCamera& eye = view->lastCameras()[0];
  keep(*frame, GetParam() ? "texture_gpu" : "texture_cpu");
  ASSERT_GT(eye.position.z, 0.5f) << "the room camera looks at the box's front";
  const float front = 0.151f;
  for (float y : {0.4f, 0.8f, 1.2f}) {
    const glm::ivec3 left = pixelAt(*frame, eye, {-0.2f, y, front});
    const glm::ivec3 right = pixelAt(*frame, eye, {0.2f, y, front});
    EXPECT_GT(left.r, 2 * left.b + 20)
        << "left of the front at y " << y << ": " << left.r << "," << left.g << "," << left.b;
    EXPECT_GT(right.b, 2 * right.r + 20)
        << "right of the front at y " << y << ": " << right.r << "," << right.g << "," << right.b;
  }
}

TEST_P(RenderLook, TexturesAreSrgbAndFactorsLinear) {
  VISTEL_MAKE_VIEW(view, options(GetParam()));
  // sRGB 128 is linear 0.2158: a grey texture and the same grey as a factor look alike.
  const auto grey = test::makePng(4, 4, [](int, int) { return glm::u8vec4(128, 128, 128, 255); });
  const float linear = 0.2158605f;
  const std::vector<MemberView> members = {
      memberAt(1, importBox(grey), -0.6f),
      memberAt(2, importBox({}, glm::vec4(linear, linear, linear, 1.0f)), 0.6f)};
  view->render(members);
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  const EyeCamera& eye = view->lastCameras()[0];
  keep(*frame, GetParam() ? "srgb_gpu" : "srgb_cpu");
  const glm::ivec3 textured = pixelAt(*frame, eye, {-0.6f, 0.8f, 0.151f});
  const glm::ivec3 factor = pixelAt(*frame, eye, {0.6f, 0.8f, 0.151f});
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(textured[c], factor[c], 3) << "channel " << c;
  // Lit in linear light and encoded to sRGB: a front face at this grey is far brighter
  // than the 0.2158 * 255 = 55 a linear write would give.
  EXPECT_GT(textured.g, 80);
}

TEST_P(RenderLook, ATextureThatDoesNotDecodeIsLeftOutWithAWarning) {
  VISTEL_MAKE_VIEW(view, options(GetParam()));
  auto avatar = std::make_shared<AvatarModel>(
      *importBox(test::makePng(4, 4, [](int, int) { return glm::u8vec4(200, 10, 10, 255); }),
                 glm::vec4(0.1f, 0.9f, 0.1f, 1.0f)));
  // Valid signature, garbage after it: as a hostile or damaged file would be.
  std::vector<std::uint8_t>& bytes = avatar->look.textures[0].encoded;
  std::fill(bytes.begin() + 8, bytes.end(), std::uint8_t{0x5A});
  ASSERT_TRUE(validateAvatar(*avatar).ok());
  const MemberView m = memberAt(1, avatar, 0.0f);
  view->render(std::span(&m, 1));
  EXPECT_NE(view->lastWarning().find("does not decode"), std::string::npos) << view->lastWarning();
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  // Drawn with its factor alone: green.
  const glm::ivec3 front = pixelAt(*frame, view->lastCameras()[0], {0.0f, 0.8f, 0.151f});
  EXPECT_GT(front.g, front.r + 40);
}

TEST_P(RenderLook, DefaultAvatarWearsItsClothes) {
  VISTEL_MAKE_VIEW(view, options(GetParam()));
  DefaultAvatarOptions small;
  small.target_vertices = 4000;
  Result<AvatarModel> made = makeDefaultAvatar(small);
  ASSERT_TRUE(made.ok()) << made.error().message;
  auto avatar = std::make_shared<const AvatarModel>(std::move(*made));
  const MemberView m = memberAt(1, avatar, 0.0f);
  view->render(std::span(&m, 1));
  EXPECT_EQ(view->lastWarning(), "");
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  keep(*frame, GetParam() ? "default_gpu" : "default_cpu");
  const EyeCamera& eye = view->lastCameras()[0];
  const std::vector<glm::mat4> rest = restModelTransforms(avatar->skeleton);
  auto front = [&](const char* joint, float ahead) {
    glm::vec3 p(rest[static_cast<std::size_t>(avatar->skeleton.find(joint))][3]);
    return pixelAt(*frame, eye, p + glm::vec3(0.0f, 0.0f, ahead));
  };
  // Denim on the shins (blue over red), skin on the face (red over blue).
  const glm::ivec3 shin = front("l_shin", 0.06f);
  EXPECT_GT(shin.b, shin.r + 15) << shin.r << "," << shin.g << "," << shin.b;
  const glm::ivec3 face = front("head", 0.1f);
  EXPECT_GT(face.r, face.b + 30) << face.r << "," << face.g << "," << face.b;
}

INSTANTIATE_TEST_SUITE_P(CpuAndGpuSkinning, RenderLook, ::testing::Values(false, true),
                         [](const auto& param_info) { return param_info.param ? "Gpu" : "Cpu"; });

TEST(RenderShadow, AvatarsDarkenTheFloorAwayFromTheLight) {
  const auto white = test::makePng(2, 2, [](int, int) { return glm::u8vec4(255, 255, 255, 255); });
  const MemberView m = memberAt(1, importBox(white), 0.0f);
  Image lit, shadowed;
  EyeCamera eye;
  for (bool shadows : {false, true}) {
    VISTEL_MAKE_VIEW(view, options(false, shadows));
    view->render(std::span(&m, 1));
    auto frame = view->readFrame();
    ASSERT_TRUE(frame.ok()) << frame.error().message;
    (shadows ? shadowed : lit) = std::move(*frame);
    eye = view->lastCameras()[0];
  }
  keep(shadowed, "shadow");
  // The key light comes from +X, +Y, +Z: the shadow falls towards -X, -Z.
  const glm::ivec3 in_shadow_lit = pixelAt(lit, eye, {-0.75f, 0.0f, -0.6f});
  const glm::ivec3 in_shadow = pixelAt(shadowed, eye, {-0.75f, 0.0f, -0.6f});
  EXPECT_LT(in_shadow.g, in_shadow_lit.g * 0.75) << in_shadow.g << " vs " << in_shadow_lit.g;
  EXPECT_TRUE(test::isBackdrop(&shadowed.pixel(0, 0)[0]));
  // On the lit side the floor is untouched.
  const glm::ivec3 sunny_lit = pixelAt(lit, eye, {0.9f, 0.0f, 0.6f});
  const glm::ivec3 sunny = pixelAt(shadowed, eye, {0.9f, 0.0f, 0.6f});
  EXPECT_EQ(sunny, sunny_lit);
  // The shadow matrix puts every point on the floor along the light.
  const glm::vec4 p = SceneRenderer::shadowProjection(0.0f) * glm::vec4(0.3f, 1.2f, -0.1f, 1.0f);
  EXPECT_NEAR(p.y, 0.0f, 1e-6f);
  EXPECT_LT(p.x, 0.3f);
  EXPECT_LT(p.z, -0.1f);
}

}  // namespace
}  // namespace vistel
