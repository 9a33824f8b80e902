// The .vavatar file: bit-identical round trip, validation of bad files.
#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// Three joints and a tetrahedron per bone: small but exercises every field.
AvatarModel makeSmallAvatar() {
  AvatarModel a;
  a.name = "tiny";
  Skeleton& s = a.skeleton;
  s.names = {"hips", "spine", "head"};
  s.parents = {kNoParent, 0, 1};
  s.rest_local.resize(3);
  s.rest_local[0].translation = {0.0f, 1.0f, 0.0f};
  s.rest_local[1].translation = {0.0f, 0.3f, 0.0f};
  s.rest_local[1].rotation = glm::angleAxis(0.3f, glm::vec3(1, 0, 0));
  s.rest_local[2].translation = {0.0f, 0.4f, 0.02f};
  computeInverseBind(s);
  SkinMesh& m = a.skin;
  m.influences = 2;
  m.positions = {{0, 1, 0}, {0.1f, 1.2f, 0}, {-0.1f, 1.3f, 0.05f}, {0, 1.5f, -0.1f}};
  m.indices = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};
  m.normals.resize(4);
  computeVertexNormals(m.positions, m.indices, m.normals);
  m.joints = {0, 1, 1, 2, 1, 0, 2, 1};
  m.weights = {0.75f, 0.25f, 0.5f, 0.5f, 1.0f, 0.0f, 0.9f, 0.1f};
  return a;
}

TEST(AvatarIo, RoundTripIsBitIdentical) {
  const AvatarModel a = makeSmallAvatar();
  ASSERT_TRUE(validateAvatar(a).ok());
  const std::vector<std::uint8_t> bytes = encodeAvatar(a);
  auto decoded = decodeAvatar(bytes, "mem");
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->name, "tiny");
  EXPECT_EQ(decoded->skeleton.names, a.skeleton.names);
  EXPECT_EQ(encodeAvatar(*decoded), bytes);
  EXPECT_EQ(avatarContentHash(bytes), avatarContentHash(encodeAvatar(*decoded)));
  EXPECT_EQ(avatarContentHash(bytes).size(), 64u);
}

TEST(AvatarIo, SaveAndLoadThroughAFile) {
  const std::string path = test::scratchDir() + "/tiny.vavatar";
  ASSERT_TRUE(saveAvatar(makeSmallAvatar(), path).ok());
  auto loaded = loadAvatar(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(encodeAvatar(*loaded), encodeAvatar(makeSmallAvatar()));
}

TEST(AvatarIo, EveryTruncationIsRejectedCleanly) {
  const std::vector<std::uint8_t> bytes = encodeAvatar(makeSmallAvatar());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    auto r = decodeAvatar(std::span(bytes.data(), n), "cut");
    ASSERT_FALSE(r.ok()) << "prefix of " << n << " bytes was accepted";
    ASSERT_NE(r.error().message.find("cut"), std::string::npos);
  }
}

TEST(AvatarIo, CorruptionIsDetected) {
  const std::vector<std::uint8_t> bytes = encodeAvatar(makeSmallAvatar());
  // Flip each byte once: checksums cover the payloads and the framing is checked, so
  // every single-byte corruption must be rejected.
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x5A;
    auto r = decodeAvatar(bad, "flip");
    EXPECT_FALSE(r.ok()) << "flipping byte " << i << " went unnoticed";
  }
}

TEST(AvatarIo, ErrorsNameTheProblem) {
  std::vector<std::uint8_t> bytes = encodeAvatar(makeSmallAvatar());
  bytes[8] = 99;  // version
  auto r = decodeAvatar(bytes, "v.vavatar");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("version 99"), std::string::npos) << r.error().message;
  auto missing = loadAvatar(test::scratchDir() + "/absent.vavatar");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("absent.vavatar"), std::string::npos);

  AvatarModel invalid = makeSmallAvatar();
  invalid.skin.weights[0] = 0.1f;  // no longer sums to 1
  const Status s = saveAvatar(invalid, test::scratchDir() + "/invalid.vavatar");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("vertex 0"), std::string::npos) << s.error().message;
}

}  // namespace
}  // namespace vistel
