// The default avatar's look: one material, a texture drawn by code, texture coordinates
// that put each body region on its own column (skin on the head, shoes on the feet).
#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "offline/synth/default_avatar.hpp"
#include "offline/synth/default_look.hpp"

namespace vistel {
namespace {

const AvatarModel& smallDefault() {
  static const AvatarModel avatar = [] {
    DefaultAvatarOptions options;
    options.target_vertices = 4000;
    Result<AvatarModel> a = makeDefaultAvatar(options);
    EXPECT_TRUE(a.ok()) << a.error().message;
    return a.ok() ? std::move(*a) : AvatarModel{};
  }();
  return avatar;
}

// The column (0 shoes, 1 trousers, 2 shirt, 3 skin) of the vertex nearest to `p`.
int columnNear(const AvatarModel& a, const glm::vec3& p) {
  std::size_t best = 0;
  for (std::size_t v = 1; v < a.skin.positions.size(); ++v) {
    if (glm::distance(a.skin.positions[v], p) < glm::distance(a.skin.positions[best], p)) best = v;
  }
  return static_cast<int>(a.look.uvs[best].x * 4.0f);
}

TEST(DefaultLook, OneMaterialWithAPngTextureAndUvsPerVertex) {
  const AvatarModel& a = smallDefault();
  ASSERT_FALSE(a.skin.positions.empty());
  const AvatarLook& look = a.look;
  ASSERT_EQ(look.materials.size(), 1u);
  ASSERT_EQ(look.textures.size(), 1u);
  EXPECT_EQ(look.materials[0].base_color_texture, 0);
  EXPECT_EQ(look.textures[0].mime, "image/png");
  EXPECT_EQ(look.textures[0].width, kDefaultLookWidth);
  EXPECT_EQ(look.textures[0].height, kDefaultLookHeight);
  EXPECT_EQ(look.uvs.size(), a.skin.positions.size());
  for (const glm::vec2& uv : look.uvs) {
    ASSERT_GT(uv.x, 0.0f);
    ASSERT_LT(uv.x, 1.0f);
    ASSERT_GT(uv.y, 0.0f);
    ASSERT_LT(uv.y, 1.0f);
  }
  EXPECT_TRUE(validateAvatar(a).ok());
  // Through the .vavatar: the look is kept.
  auto d = decodeAvatar(encodeAvatar(a), "default.vavatar");
  ASSERT_TRUE(d.ok()) << d.error().message;
  EXPECT_EQ(d->look.textures[0].encoded, look.textures[0].encoded);
}

TEST(DefaultLook, RegionsLandOnTheirColumns) {
  const AvatarModel& a = smallDefault();
  ASSERT_FALSE(a.skin.positions.empty());
  const std::vector<glm::mat4> rest = restModelTransforms(a.skeleton);
  auto at = [&](const char* joint) {
    return glm::vec3(rest[static_cast<std::size_t>(a.skeleton.find(joint))][3]);
  };
  EXPECT_EQ(columnNear(a, at("head") + glm::vec3(0, 0.05f, 0.1f)), 3);  // face: skin
  EXPECT_EQ(columnNear(a, at("l_toes")), 0);                            // shoes
  EXPECT_EQ(columnNear(a, at("r_shin")), 1);                            // trousers
  EXPECT_EQ(columnNear(a, at("chest") + glm::vec3(0, 0, 0.15f)), 2);    // shirt
  EXPECT_EQ(columnNear(a, at("l_hand")), 3);                            // skin
  // The texture: skin-coloured in the skin column, darker shoes.
  const std::vector<std::uint8_t> px = defaultLookPixels();
  const std::uint8_t* skin = &px[(10 * kDefaultLookWidth + 56) * 4];
  const std::uint8_t* shoe = &px[(120 * kDefaultLookWidth + 8) * 4];
  EXPECT_GT(skin[0], skin[2] + 40);
  EXPECT_LT(shoe[0] + shoe[1] + shoe[2], skin[0] + skin[1] + skin[2]);
}

TEST(DefaultLook, IsDeterministic) {
  const AvatarModel& a = smallDefault();
  ASSERT_FALSE(a.skin.positions.empty());
  const AvatarLook again = makeDefaultLook(a);
  EXPECT_EQ(again.uvs, a.look.uvs);
  EXPECT_EQ(again.textures[0].encoded, a.look.textures[0].encoded);
}

}  // namespace
}  // namespace vistel
