// Building the implicit model offline: the primitive map, vertex classes, the graph.
#include <gtest/gtest.h>

#include "common/deform/implicit_codec.hpp"
#include "offline/build/build_model.hpp"
#include "offline/build/primitive_map.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

TEST(PrimitiveMap, DefaultHumanoidMapParses) {
  Result<PrimitiveMapSpec> map = loadPrimitiveMap("config/avatars/humanoid.toml");
  ASSERT_TRUE(map.ok()) << map.error().message;
  int limbs = 0, joints = 0, bones = 0;
  for (const PrimitiveSpec& p : map->primitives) {
    (p.role == PrimitiveRole::kLimb ? limbs : p.role == PrimitiveRole::kJoint ? joints : bones)++;
  }
  EXPECT_EQ(limbs,
            16);  // head, neck, torso, pelvis, 2 x (upper arm, forearm, hand, thigh, shin, foot)
  EXPECT_EQ(joints, 10);  // shoulders, elbows, wrists, hips, knees
  EXPECT_EQ(bones, 4);    // elbows and knees
  const PrimitiveSpec* torso = map->find("torso");
  ASSERT_NE(torso, nullptr);
  EXPECT_EQ(torso->shape, ShapeKind::kOffsetPolygon);
}

TEST(PrimitiveMap, ErrorsNameLineAndReason) {
  const auto error_of = [](std::string_view text) {
    Result<PrimitiveMapSpec> r = parsePrimitiveMap(text, "m.toml");
    return r.ok() ? std::string() : r.error().message;
  };
  EXPECT_NE(error_of("[[primitive]]\nname = \"a\"\nshape = \"sphere\"\nbone = \"x\"\ncolour = 3\n")
                .find("m.toml:5: unknown primitive key 'colour'"),
            std::string::npos);
  EXPECT_NE(error_of("[[primitive]]\nname = \"a\"\nshape = \"blob\"\nbone = \"x\"\n")
                .find("shape 'blob'"),
            std::string::npos);
  EXPECT_NE(
      error_of("[[primitive]]\nname = \"j\"\nrole = \"joint\"\nshape = \"sphere\"\nbone = \"x\"\n"
               "at = \"x\"\nbetween = [\"a\", \"b\"]\n")
          .find("is not a limb primitive"),
      std::string::npos);
  EXPECT_NE(error_of("iso = 2.0\n[[primitive]]\nname = \"a\"\nshape = \"sphere\"\nbone = \"x\"\n")
                .find("iso"),
            std::string::npos);
  EXPECT_NE(
      error_of("no_collide = [[\"a\", \"zz\"]]\n[[primitive]]\nname = \"a\"\nshape = \"sphere\"\n"
               "bone = \"x\"\n")
          .find("no_collide names unknown primitive 'zz'"),
      std::string::npos);
  EXPECT_NE(error_of("[[primitive]\n").find("m.toml:1"), std::string::npos);
  EXPECT_NE(error_of("").find("no [[primitive]]"), std::string::npos);
}

TEST(Build, ArmClassesGraphAndFit) {
  const AvatarModel avatar = test::makeArmAvatar();
  Result<PrimitiveMapSpec> spec = parsePrimitiveMap(test::armMapToml(), "arm.toml");
  ASSERT_TRUE(spec.ok());
  BuildReport report;
  std::vector<float> progress;
  BuildOptions opt;
  opt.progress = [&](float f, std::string_view) { progress.push_back(f); };
  Result<ImplicitModel> model = buildImplicitModel(avatar, *spec, nullptr, opt, &report);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_TRUE(report.warnings.empty());
  ASSERT_EQ(report.primitives, (std::vector<std::string>{"upper", "fore", "elbow", "elbow_bone"}));
  EXPECT_EQ(progress.back(), 1.0f);
  const ImplicitModel& m = *model;
  // Fitted radii: the tube's 4 cm.
  EXPECT_NEAR(m.primitives.items[0].shape.radius_a, 0.04f, 2e-3f);
  EXPECT_NEAR(m.primitives.items[0].r_in, 1.0f, 0.02f);
  EXPECT_NEAR(m.primitives.items[0].r_in / m.primitives.items[0].r_out, 0.7f, 1e-3f);
  EXPECT_FALSE(m.primitives.items[3].collides);
  // Graph: the elbow blends the two bones; the bones collide with each other (beyond the
  // joint), the joint does not collide with its own limbs.
  ASSERT_EQ(m.graph.blends.size(), 1u);
  EXPECT_EQ(m.graph.blends[0].joint, 2);
  EXPECT_TRUE(m.graph.collides(0, 1));
  EXPECT_FALSE(m.graph.collides(0, 2));
  EXPECT_FALSE(m.graph.collides(1, 3));
  // Classes: joint vertices exactly where both weights are large enough.
  int joint = 0;
  for (int v = 0; v < avatar.skin.vertexCount(); ++v) {
    const float w1 = avatar.skin.weights[static_cast<std::size_t>(2 * v + 1)];
    const bool expect_joint = std::min(w1, 1.0f - w1) >= spec->joint_weight;
    const VertexClass cls = m.calibration.vertex_class[static_cast<std::size_t>(v)];
    EXPECT_EQ(cls == VertexClass::kJoint, expect_joint) << "vertex " << v;
    if (cls == VertexClass::kJoint) {
      ++joint;
      const auto& p = m.calibration.prims[static_cast<std::size_t>(v)];
      EXPECT_EQ(p[0], 2);
      EXPECT_EQ(p[1], w1 < 0.5f ? 0 : 1) << "own side first";
      EXPECT_EQ(p[2], w1 < 0.5f ? 1 : 0);
    }
  }
  EXPECT_GT(joint, 50);
  EXPECT_EQ(report.calibration.joint, joint);
}

// Calibration::own_weight: the share of a vertex's skin its own field models. Across the
// elbow the blend of the two limbs is the joint's, so the whole tube counts 1; skin weight
// moved to the tip joint, which no primitive follows, does not count.
TEST(Build, OwnWeightIsTheSkinTheFieldModels) {
  AvatarModel avatar = test::makeArmAvatar();
  Result<PrimitiveMapSpec> spec = parsePrimitiveMap(test::armMapToml(), "arm.toml");
  ASSERT_TRUE(spec.ok());
  Result<ImplicitModel> model = buildImplicitModel(avatar, *spec, nullptr);
  ASSERT_TRUE(model.ok()) << model.error().message;
  const Calibration& cal = model->calibration;
  ASSERT_EQ(cal.own_weight.size(), static_cast<std::size_t>(avatar.skin.vertexCount()));
  int blended = 0;
  for (int v = 0; v < avatar.skin.vertexCount(); ++v) {
    const auto vi = static_cast<std::size_t>(v);
    const float w1 = avatar.skin.weights[2 * vi + 1];
    if (w1 > 0.0f && w1 < 1.0f) ++blended;
    EXPECT_NEAR(cal.own_weight[vi], 1.0f, 1e-5f) << "vertex " << v;
  }
  EXPECT_GT(blended, 50);

  // A quarter of every upper-arm vertex's weight handed to the tip joint.
  const int tip = avatar.skeleton.find("tip");
  ASSERT_GE(tip, 0);
  std::vector<int> moved;
  for (int v = 0; v < avatar.skin.vertexCount(); ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (avatar.skin.weights[2 * vi + 1] != 0.0f) continue;  // upper arm alone
    avatar.skin.weights[2 * vi] = 0.75f;
    avatar.skin.joints[2 * vi + 1] = static_cast<std::uint16_t>(tip);
    avatar.skin.weights[2 * vi + 1] = 0.25f;
    moved.push_back(v);
  }
  ASSERT_GT(moved.size(), 50u);
  Result<ImplicitModel> handed = buildImplicitModel(avatar, *spec, nullptr);
  ASSERT_TRUE(handed.ok()) << handed.error().message;
  for (const int v : moved) {
    if (handed->calibration.vertex_class[static_cast<std::size_t>(v)] == VertexClass::kFree)
      continue;
    EXPECT_NEAR(handed->calibration.own_weight[static_cast<std::size_t>(v)], 0.75f, 1e-5f)
        << "vertex " << v;
  }
  // It survives the model's file.
  Result<ImplicitModel> decoded = decodeImplicitModel(
      encodeImplicitModel(*handed), avatar.skeleton.jointCount(), avatar.skin.vertexCount());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->calibration.own_weight, handed->calibration.own_weight);
}

TEST(Build, MissingJointsSkipPrimitivesWithWarnings) {
  AvatarModel avatar = test::makeArmAvatar();
  std::string toml = test::armMapToml();
  toml += "[[primitive]]\nname = \"hand\"\nshape = \"sphere\"\nbone = \"wrist\"\n";
  Result<PrimitiveMapSpec> spec = parsePrimitiveMap(toml, "arm.toml");
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  BuildReport report;
  Result<ImplicitModel> model = buildImplicitModel(avatar, *spec, nullptr, {}, &report);
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->primitives.items.size(), 4u);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("hand"), std::string::npos);
  // A joint map renames the skeleton's joints.
  JointMap map;
  map.canonical = {"upper", "fore", "tip"};
  map.joint = {"u", "f", "t"};
  avatar.skeleton.names = {"u", "f", "t"};
  Result<ImplicitModel> renamed = buildImplicitModel(avatar, *spec, &map, {}, &report);
  ASSERT_TRUE(renamed.ok()) << renamed.error().message;
  EXPECT_EQ(encodeImplicitModel(*renamed), encodeImplicitModel(*model));
}

}  // namespace
}  // namespace vistel
