// alphaMode BLEND on the client's renderer (RoomView, EGL offscreen): a box whose material
// is 40 % opaque shows what is behind it mixed with its own colour in linear light, where
// it used to be drawn as MASK (cut away entirely below alpha 0.5).
#include <cmath>
#include <memory>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/view/room_view.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/glb/gltf_export.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/gltf/gltf_look_models.hpp"
#include "tests/render/render_checks.hpp"

namespace vistel {
namespace {

std::shared_ptr<const AvatarModel> box(const glm::vec4& factor, AlphaMode mode) {
  auto glb = encodeGlb(test::texturedBoxScene({}, factor));
  EXPECT_TRUE(glb.ok()) << glb.error().message;
  auto avatar = importGltfAvatarFromMemory(*glb, "box.glb");
  EXPECT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_FALSE(avatar->look.materials.empty());
  for (AvatarMaterial& m : avatar->look.materials) m.alpha_mode = mode;
  auto loaded = decodeAvatar(encodeAvatar(*avatar), "box.vavatar");
  EXPECT_TRUE(loaded.ok()) << loaded.error().message;
  return std::make_shared<const AvatarModel>(std::move(*loaded));
}

double decode(int v) {
  const double c = v / 255.0;
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}
int encode(double l) {
  const double s = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1 / 2.4) - 0.055;
  return static_cast<int>(std::lround(255.0 * s));
}

class RenderBlend : public ::testing::TestWithParam<bool> {};

TEST_P(RenderBlend, BlendedMaterialsMixWithWhatIsBehindInLinearLight) {
  ViewOptions o;
  o.width = 320;
  o.height = 240;
  o.offscreen = true;
  o.show_tags = false;
  o.gpu_skinning = GetParam();
  o.shadows = false;
  o.msaa_samples = 4;
  VISTEL_MAKE_VIEW(view, o);
  const glm::vec3 red(0.8f, 0.05f, 0.05f);
  // The pixel of the box's front face, centre: opaque, cut away (MASK below its cutoff),
  // and blended.
  const auto shoot = [&](float alpha, AlphaMode mode) {
    auto avatar = box(glm::vec4(red, alpha), mode);
    const std::vector<MemberView> members = {
        MemberView{1, "", avatar, restPosture(avatar->skeleton), glm::mat4(1.0f), false}};
    view->render(members);
    auto frame = view->readFrame();
    EXPECT_TRUE(frame.ok()) << frame.error().message;
    int x = 0, row = 0;
    EXPECT_TRUE(test::pixelOf(view->lastCameras()[0], frame->height, {0.0f, 0.8f, 0.151f}, x, row));
    const std::uint8_t* px = frame->pixel(x, row);
    return glm::ivec3(px[0], px[1], px[2]);
  };
  const glm::ivec3 opaque = shoot(1.0f, AlphaMode::kOpaque);
  const glm::ivec3 behind = shoot(0.4f, AlphaMode::kMask);
  const glm::ivec3 blended = shoot(0.4f, AlphaMode::kBlend);
  std::printf("[ measure  ] opaque (%d %d %d), behind (%d %d %d), blended (%d %d %d)\n", opaque.r,
              opaque.g, opaque.b, behind.r, behind.g, behind.b, blended.r, blended.g, blended.b);
  ASSERT_GT(opaque.r, behind.r + 40) << "the box is red, what is behind it is not";
  for (int c = 0; c < 3; ++c) {
    const int want = encode(0.4 * decode(opaque[c]) + 0.6 * decode(behind[c]));
    EXPECT_NEAR(blended[c], want, 4) << "channel " << c;
  }
  EXPECT_GT(blended.r, behind.r + 20);
  EXPECT_LT(blended.r, opaque.r - 10);
}

// Two members: the first a blended red box, the second an opaque one behind it. Drawn in
// member order the blended box (depth not written) would be painted over by the box behind;
// every member's opaque parts first, then the blended ones far to near, keep the mix.
TEST_P(RenderBlend, ABlendedMemberDoesNotHideAMemberDrawnAfterIt) {
  ViewOptions o;
  o.width = 320;
  o.height = 240;
  o.offscreen = true;
  o.show_tags = false;
  o.gpu_skinning = GetParam();
  o.shadows = false;
  o.msaa_samples = 4;
  VISTEL_MAKE_VIEW(view, o);
  const glm::vec3 red(0.8f, 0.05f, 0.05f);
  const glm::vec3 green(0.05f, 0.7f, 0.1f);
  auto back = box(glm::vec4(green, 1.0f), AlphaMode::kOpaque);
  const glm::mat4 behind_it = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, -0.6f));
  const auto shoot = [&](float alpha, AlphaMode mode) {
    auto front = box(glm::vec4(red, alpha), mode);
    const std::vector<MemberView> members = {
        MemberView{1, "", front, restPosture(front->skeleton), glm::mat4(1.0f), false},
        MemberView{2, "", back, restPosture(back->skeleton), behind_it, false}};
    view->render(members);
    auto frame = view->readFrame();
    EXPECT_TRUE(frame.ok()) << frame.error().message;
    int x = 0, row = 0;
    EXPECT_TRUE(test::pixelOf(view->lastCameras()[0], frame->height, {0.0f, 0.8f, 0.151f}, x, row));
    const std::uint8_t* px = frame->pixel(x, row);
    return glm::ivec3(px[0], px[1], px[2]);
  };
  const glm::ivec3 opaque = shoot(1.0f, AlphaMode::kOpaque);
  const glm::ivec3 behind = shoot(0.4f, AlphaMode::kMask);  // the green box shows through
  const glm::ivec3 blended = shoot(0.4f, AlphaMode::kBlend);
  std::printf("[ measure  ] opaque (%d %d %d), behind (%d %d %d), blended (%d %d %d)\n", opaque.r,
              opaque.g, opaque.b, behind.r, behind.g, behind.b, blended.r, blended.g, blended.b);
  ASSERT_GT(behind.g, opaque.g + 40) << "the green box is behind the red one";
  for (int c = 0; c < 3; ++c) {
    const int want = encode(0.4 * decode(opaque[c]) + 0.6 * decode(behind[c]));
    EXPECT_NEAR(blended[c], want, 4) << "channel " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(CpuAndGpuSkinning, RenderBlend, ::testing::Values(false, true),
                         [](const auto& p) { return p.param ? "Gpu" : "Cpu"; });

}  // namespace
}  // namespace vistel
