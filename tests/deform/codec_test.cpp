// The implicit model's bytes: round trip bit-identical, every prefix and corruption
// rejected with an error (no crash).
#include <cstring>

#include <gtest/gtest.h>

#include "common/base/bytes.hpp"
#include "common/deform/implicit_codec.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

TEST(Codec, RoundTripIsBitIdentical) {
  auto arm = test::armBody();
  const ImplicitModel& m = arm->model;
  const std::vector<std::uint8_t> bytes = encodeImplicitModel(m);
  Result<ImplicitModel> back =
      decodeImplicitModel(bytes, arm->skeleton.jointCount(), arm->mesh.vertexCount());
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(encodeImplicitModel(*back), bytes);
  ASSERT_EQ(back->primitives.items.size(), m.primitives.items.size());
  for (std::size_t i = 0; i < m.primitives.items.size(); ++i) {
    const Primitive& a = m.primitives.items[i];
    const Primitive& b = back->primitives.items[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(std::memcmp(&a.shape.a, &b.shape.a, sizeof(glm::vec3)), 0);
    EXPECT_EQ(a.shape.length, b.shape.length);
    EXPECT_EQ(a.r_in, b.r_in);
    EXPECT_EQ(a.weight, b.weight);
    EXPECT_EQ(a.skin_weight.n, b.skin_weight.n);
    EXPECT_EQ(a.skin_weight.values, b.skin_weight.values);
    EXPECT_EQ(a.skin_weight.max_value, b.skin_weight.max_value);
  }
  EXPECT_GT(m.primitives.items[1].skin_weight.n, 0) << "the forearm defines vertices: a grid";
  EXPECT_EQ(back->graph.collide_matrix, m.graph.collide_matrix);
  EXPECT_EQ(back->calibration.w, m.calibration.w);
  EXPECT_EQ(back->calibration.ring, m.calibration.ring);
  // A rigid ball's infinite stiffness survives.
  Result<BallBody> ball = makeBall(BallSpec{});
  ASSERT_TRUE(ball.ok());
  const auto ball_bytes = encodeImplicitModel(ball->model);
  Result<ImplicitModel> ball_back = decodeImplicitModel(ball_bytes, 1, ball->mesh.vertexCount());
  ASSERT_TRUE(ball_back.ok()) << ball_back.error().message;
  EXPECT_TRUE(std::isinf(ball_back->primitives.items[0].stiffness));
}

TEST(Codec, EveryPrefixFailsCleanly) {
  auto arm = test::armBody();
  const std::vector<std::uint8_t> bytes = encodeImplicitModel(arm->model);
  // Every prefix of the primitive section and the graph; a sample of the calibration's.
  for (std::size_t n = 0; n < bytes.size(); n += (n < 4000 ? 1 : 97)) {
    Result<ImplicitModel> r =
        decodeImplicitModel(std::span(bytes).first(n), 3, arm->mesh.vertexCount());
    ASSERT_FALSE(r.ok()) << "prefix " << n;
    EXPECT_FALSE(r.error().message.empty());
  }
  // Trailing bytes are an error too.
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decodeImplicitModel(longer, 3, arm->mesh.vertexCount()).ok());
}

TEST(Codec, CorruptValuesAreRejectedWithReasons) {
  auto arm = test::armBody();
  const int nv = arm->mesh.vertexCount();
  {
    ImplicitModel m = arm->model;
    m.primitives.items[1].bone = 7;
    const auto r = decodeImplicitModel(encodeImplicitModel(m), 3, nv);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("bone out of range"), std::string::npos) << r.error().message;
  }
  {
    ImplicitModel m = arm->model;
    m.primitives.items[0].r_in = std::nanf("");
    EXPECT_FALSE(decodeImplicitModel(encodeImplicitModel(m), 3, nv).ok());
  }
  {
    ImplicitModel m = arm->model;
    ASSERT_FALSE(m.primitives.items[1].skin_weight.values.empty());
    m.primitives.items[1].skin_weight.values[3] = 0.0f;
    const auto r = decodeImplicitModel(encodeImplicitModel(m), 3, nv);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("skin weight sample out of range"), std::string::npos)
        << r.error().message;
  }
  {
    ImplicitModel m = arm->model;
    m.calibration.prims[5][0] = 99;
    const auto r = decodeImplicitModel(encodeImplicitModel(m), 3, nv);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("vertex 5"), std::string::npos) << r.error().message;
  }
  {
    ImplicitModel m = arm->model;
    m.calibration.ring[3] = static_cast<std::uint32_t>(nv + 4);
    EXPECT_FALSE(decodeImplicitModel(encodeImplicitModel(m), 3, nv).ok());
  }
  // A different skin.
  EXPECT_FALSE(decodeImplicitModel(encodeImplicitModel(arm->model), 3, nv + 1).ok());
  // Random byte flips never crash (they fail or decode to a valid model).
  std::vector<std::uint8_t> bytes = encodeImplicitModel(arm->model);
  for (std::size_t i = 0; i < 3000 && i < bytes.size(); i += 7) {
    std::vector<std::uint8_t> b = bytes;
    b[i] ^= 0xA5;
    Result<ImplicitModel> r = decodeImplicitModel(b, 3, nv);
    if (r.ok()) {
      EXPECT_TRUE(validateImplicitModel(*r, 3, nv).ok());
    }
  }
}

// A version 1 calibration (before own weights) still reads, with none (no fade); the
// current version carries them; an unknown version is refused by name.
TEST(Codec, CalibrationVersionOneReadsWithoutOwnWeights) {
  auto arm = test::armBody();
  const Calibration& cal = arm->model.calibration;
  ASSERT_EQ(cal.own_weight.size(), static_cast<std::size_t>(arm->mesh.vertexCount()));
  std::vector<std::uint8_t> v2;
  ByteWriter w2(v2);
  encodeCalibration(cal, w2);
  Result<Calibration> back = decodeCalibration(v2, arm->model.primitives, arm->mesh.vertexCount());
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->own_weight, cal.own_weight);

  // Version 1: the same bytes without the own weights' count and array.
  const std::size_t nv = cal.vertex_class.size();
  const std::size_t at = 8 + nv * (1 + 8 + 4 + 4 + 1);
  std::vector<std::uint8_t> v1(v2.begin(), v2.begin() + static_cast<std::ptrdiff_t>(at));
  v1.insert(v1.end(), v2.begin() + static_cast<std::ptrdiff_t>(at + 4 + 4 * nv), v2.end());
  v1[0] = 1;
  Result<Calibration> old = decodeCalibration(v1, arm->model.primitives, arm->mesh.vertexCount());
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_TRUE(old->own_weight.empty());
  EXPECT_EQ(old->w, cal.w);
  EXPECT_EQ(old->ring, cal.ring);

  v2[0] = 9;
  Result<Calibration> unknown =
      decodeCalibration(v2, arm->model.primitives, arm->mesh.vertexCount());
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("version 9"), std::string::npos)
      << unknown.error().message;
}

}  // namespace
}  // namespace vistel
