// The look in the .vavatar (format version 2, chunk LOOK): round trip, version 1 files
// still read, and validation of bad looks.
#include <cmath>
#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"

namespace vistel {
namespace {

// A tetrahedron on two joints with a two-material look and two (fake but well-signed)
// textures.
AvatarModel makeLookAvatar() {
  AvatarModel a;
  a.name = "looky";
  Skeleton& s = a.skeleton;
  s.names = {"hips", "spine"};
  s.parents = {kNoParent, 0};
  s.rest_local.resize(2);
  s.rest_local[0].translation = {0.0f, 1.0f, 0.0f};
  s.rest_local[1].translation = {0.0f, 0.3f, 0.0f};
  computeInverseBind(s);
  SkinMesh& m = a.skin;
  m.influences = 1;
  m.positions = {{0, 1, 0}, {0.1f, 1.2f, 0}, {-0.1f, 1.3f, 0.05f}, {0, 1.5f, -0.1f}};
  m.indices = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};
  m.normals.resize(4);
  computeVertexNormals(m.positions, m.indices, m.normals);
  m.joints = {0, 0, 1, 1};
  m.weights = {1, 1, 1, 1};
  AvatarLook& look = a.look;
  look.uvs = {{0, 0}, {1, 0}, {1, 1}, {0.25f, 0.75f}};
  AvatarTexture png;
  png.name = "albedo";
  png.mime = "image/png";
  png.width = 4;
  png.height = 2;
  png.encoded = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A, 1, 2, 3};
  AvatarTexture jpg;
  jpg.name = "normal";
  jpg.mime = "image/jpeg";
  jpg.width = 8;
  jpg.height = 8;
  jpg.encoded = {0xFF, 0xD8, 0xFF, 0xE0, 9, 9};
  look.textures = {png, jpg};
  AvatarMaterial body;
  body.name = "body";
  body.base_color = {0.8f, 0.5f, 0.25f, 1.0f};
  body.base_color_texture = 0;
  body.normal_texture = 1;
  body.normal_scale = 0.7f;
  body.roughness = 0.6f;
  AvatarMaterial hair;
  hair.name = "hair";
  hair.alpha_mode = AlphaMode::kMask;
  hair.alpha_cutoff = 0.3f;
  hair.double_sided = true;
  look.materials = {body, hair};
  look.submeshes = {{0, 6, 0}, {6, 6, 1}};
  return a;
}

TEST(AvatarLook, RoundTripKeepsEveryFieldAndBytes) {
  const AvatarModel a = makeLookAvatar();
  ASSERT_TRUE(validateAvatar(a).ok()) << validateAvatar(a).error().message;
  const std::vector<std::uint8_t> bytes = encodeAvatar(a);
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  EXPECT_EQ(version, 2u);
  EXPECT_EQ(kAvatarFormatVersion, 2u);
  auto d = decodeAvatar(bytes, "mem");
  ASSERT_TRUE(d.ok()) << d.error().message;
  EXPECT_EQ(d->look.uvs, a.look.uvs);
  ASSERT_EQ(d->look.textures.size(), 2u);
  EXPECT_EQ(d->look.textures[0].encoded, a.look.textures[0].encoded);
  EXPECT_EQ(d->look.textures[1].mime, "image/jpeg");
  EXPECT_EQ(d->look.textures[1].width, 8);
  ASSERT_EQ(d->look.materials.size(), 2u);
  EXPECT_EQ(d->look.materials[0].base_color, a.look.materials[0].base_color);
  EXPECT_EQ(d->look.materials[0].normal_texture, 1);
  EXPECT_FLOAT_EQ(d->look.materials[0].normal_scale, 0.7f);
  EXPECT_EQ(d->look.materials[1].alpha_mode, AlphaMode::kMask);
  EXPECT_TRUE(d->look.materials[1].double_sided);
  ASSERT_EQ(d->look.submeshes.size(), 2u);
  EXPECT_EQ(d->look.submeshes[1].first_index, 6u);
  EXPECT_EQ(encodeAvatar(*d), bytes);
  EXPECT_EQ(d->look.textureBytes(), 11u + 6u);
}

TEST(AvatarLook, EveryTruncationOfTheLookIsRejectedCleanly) {
  const std::vector<std::uint8_t> bytes = encodeAvatar(makeLookAvatar());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    ASSERT_FALSE(decodeAvatar(std::span(bytes.data(), n), "cut").ok()) << n;
  }
}

TEST(AvatarLook, VersionOneFilesStillRead) {
  AvatarModel a = makeLookAvatar();
  a.look = AvatarLook{};
  std::vector<std::uint8_t> bytes = encodeAvatar(a);
  const std::uint32_t one = 1;
  std::memcpy(bytes.data() + 8, &one, 4);  // what the previous build wrote: no LOOK, v1
  auto d = decodeAvatar(bytes, "old.vavatar");
  ASSERT_TRUE(d.ok()) << d.error().message;
  EXPECT_TRUE(d->look.empty());
  EXPECT_EQ(d->skeleton.names, a.skeleton.names);
  // A version from the future is refused with both versions named.
  const std::uint32_t future = 3;
  std::memcpy(bytes.data() + 8, &future, 4);
  auto f = decodeAvatar(bytes, "new.vavatar");
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.error().message.find("format version 3"), std::string::npos) << f.error().message;
}

TEST(AvatarLook, AnAvatarWithoutALookWritesNoLookChunk) {
  AvatarModel a = makeLookAvatar();
  a.look = AvatarLook{};
  const std::vector<std::uint8_t> bytes = encodeAvatar(a);
  const std::string text(bytes.begin(), bytes.end());
  EXPECT_EQ(text.find("LOOK"), std::string::npos);
}

TEST(AvatarLook, BadLooksAreRefusedNamingThePart) {
  auto expectBad = [](AvatarModel a, std::string_view words) {
    const Status v = validateAvatar(a);
    ASSERT_FALSE(v.ok()) << words;
    EXPECT_NE(v.error().message.find(words), std::string::npos) << v.error().message;
    // The decoder refuses what the encoder was made to write.
    auto d = decodeAvatar(encodeAvatar(a), "bad.vavatar");
    ASSERT_FALSE(d.ok()) << words;
    EXPECT_NE(d.error().message.find("LOOK"), std::string::npos) << d.error().message;
  };
  AvatarModel a = makeLookAvatar();
  a.look.uvs.pop_back();
  expectBad(a, "texture coordinates for 4 vertices");
  a = makeLookAvatar();
  a.look.materials[0].base_color_texture = 5;
  expectBad(a, "base colour texture 5");
  a = makeLookAvatar();
  a.look.textures[0].encoded[1] = 'X';
  expectBad(a, "not a PNG");
  a = makeLookAvatar();
  a.look.textures[1].mime = "image/webp";
  expectBad(a, "image/webp");
  a = makeLookAvatar();
  a.look.submeshes[1].first_index = 3;
  expectBad(a, "submesh 1 starts at index 3");
  a = makeLookAvatar();
  a.look.submeshes.pop_back();
  expectBad(a, "cover 6 indices");
  a = makeLookAvatar();
  a.look.materials[0].base_color.g = 1.5f;
  expectBad(a, "base colour component 1");
  a = makeLookAvatar();
  a.look.uvs[2].x = std::nanf("");
  expectBad(a, "vertex 2: non-finite");
}

TEST(AvatarLook, EffectiveSubmeshesCoverEverythingWhenNoneAreGiven) {
  AvatarLook look;
  EXPECT_EQ(effectiveSubmeshes(look, 12).size(), 1u);
  EXPECT_EQ(effectiveSubmeshes(look, 12)[0].material, -1);
  look.materials.resize(1);
  EXPECT_EQ(effectiveSubmeshes(look, 12)[0].material, 0);
  EXPECT_EQ(effectiveSubmeshes(look, 12)[0].index_count, 12u);
}

// Run with --gtest_also_run_disabled_tests and VISTEL_WRITE_SEEDS_DIR set: writes the
// look avatar there (the seed in tests/fuzz/corpus/avatar was made this way).
TEST(AvatarLook, DISABLED_WritesAFuzzSeedWhenAsked) {
  const char* dir = std::getenv("VISTEL_WRITE_SEEDS_DIR");
  if (dir == nullptr) GTEST_SKIP() << "VISTEL_WRITE_SEEDS_DIR is not set";
  EXPECT_TRUE(saveAvatar(makeLookAvatar(), std::string(dir) + "/look.vavatar").ok());
}

}  // namespace
}  // namespace vistel
