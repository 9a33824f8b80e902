// The implicit model inside the .vavatar file: bit-identical round trip, validation.
#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

AvatarModel builtArm() {
  AvatarModel avatar = test::makeArmAvatar();
  auto spec = parsePrimitiveMap(test::armMapToml(), "arm.toml");
  EXPECT_TRUE(spec.ok()) << spec.error().message;
  auto model = buildImplicitModel(avatar, *spec, nullptr);
  EXPECT_TRUE(model.ok()) << model.error().message;
  avatar.implicit = std::move(*model);
  return avatar;
}

TEST(AvatarFile, ImplicitModelRoundTripsBitIdentically) {
  const AvatarModel avatar = builtArm();
  ASSERT_TRUE(validateAvatar(avatar).ok());
  const std::vector<std::uint8_t> bytes = encodeAvatar(avatar);
  auto decoded = decodeAvatar(bytes, "arm.vavatar");
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  ASSERT_TRUE(decoded->implicit.has_value());
  EXPECT_EQ(decoded->implicit->primitives.items.size(), avatar.implicit->primitives.items.size());
  EXPECT_EQ(encodeAvatar(*decoded), bytes);

  // Without the implicit model the file is smaller and loads as rigid-only.
  AvatarModel rigid = avatar;
  rigid.implicit.reset();
  auto rigid_decoded = decodeAvatar(encodeAvatar(rigid), "rigid.vavatar");
  ASSERT_TRUE(rigid_decoded.ok());
  EXPECT_FALSE(rigid_decoded->implicit.has_value());
}

TEST(AvatarFile, DamagedImplicitChunksAreRejected) {
  const std::vector<std::uint8_t> bytes = encodeAvatar(builtArm());
  // Truncations and single-byte corruptions at 300 places spread over the file (the
  // implicit chunks are its second half) all fail.
  const std::size_t step = bytes.size() / 300 + 1;
  for (std::size_t n = 0; n < bytes.size(); n += step) {
    ASSERT_FALSE(decodeAvatar(std::span(bytes.data(), n), "cut").ok()) << n;
  }
  for (std::size_t i = 5; i < bytes.size(); i += step) {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x21;
    EXPECT_FALSE(decodeAvatar(bad, "flip").ok()) << "byte " << i;
  }
}

}  // namespace
}  // namespace vistel
