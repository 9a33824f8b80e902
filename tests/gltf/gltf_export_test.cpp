#include "common/glb/gltf_export.hpp"

#include <algorithm>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/glb/glb_container.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

AvatarModel chainAvatar() {
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(test::makeChainGltf().file.glb(), "chain.glb");
  EXPECT_TRUE(avatar.ok()) << avatar.error().message;
  return std::move(*avatar);
}

// A posture that bends every joint a little (deterministic).
Posture bentPosture(const Skeleton& s, float amount) {
  Posture p = restPosture(s);
  for (std::size_t j = 0; j < p.rotations.size(); ++j) {
    const glm::vec3 axis = glm::normalize(glm::vec3(std::sin(1.3f * j), 1.0f, std::cos(0.7f * j)));
    p.rotations[j] = glm::normalize(p.rotations[j] * glm::angleAxis(amount, axis));
  }
  p.root_translation += glm::vec3(0.1f, 0.0f, -0.2f);
  return p;
}

struct Posed {
  std::vector<glm::mat4> model;
  std::vector<glm::vec3> positions, normals;
};

Posed pose(const AvatarModel& a, const Posture& posture, SkinningMethod method) {
  const std::size_t nj = a.skeleton.names.size(), nv = a.skin.positions.size();
  Posed out;
  out.model.resize(nj);
  std::vector<glm::mat4> skin(nj);
  std::vector<DualQuat> dq(nj);
  out.positions.resize(nv);
  out.normals.resize(nv);
  poseSkeleton(a.skeleton, posture, out.model);
  skinningMatrices(a.skeleton, out.model, skin);
  skinMesh(a.skin, method, skin, dq, out.positions, out.normals);
  return out;
}

nlohmann::json glbJson(const std::vector<std::uint8_t>& bytes) {
  Result<GlbChunks> chunks = parseGlbContainer(bytes, "out.glb");
  EXPECT_TRUE(chunks.ok());
  return nlohmann::json::parse(chunks->json.begin(), chunks->json.end());
}

// Export -> import gives the posed vertices, the joint names and the weights back.
void expectRoundTrip(const AvatarModel& a, const Posture& posture, SkinningMethod method) {
  const Posed posed = pose(a, posture, method);
  Result<std::vector<std::uint8_t>> bytes =
      encodeGlb(posedAvatarScene(a, posed.model, posed.positions, posed.normals));
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  GltfImportReport report;
  Result<AvatarModel> back = importGltfAvatarFromMemory(*bytes, "posed.glb", "", {}, &report);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_FALSE(report.rest_from_inverse_bind);
  EXPECT_FALSE(report.normals_computed);
  EXPECT_EQ(back->skeleton.names, a.skeleton.names);
  EXPECT_EQ(back->skeleton.parents, a.skeleton.parents);
  EXPECT_EQ(back->skin.indices, a.skin.indices);
  ASSERT_EQ(back->skin.positions.size(), posed.positions.size());
  for (std::size_t v = 0; v < posed.positions.size(); ++v) {
    ASSERT_LT(glm::distance(back->skin.positions[v], posed.positions[v]), 1e-5f) << "vertex " << v;
    ASSERT_LT(glm::distance(back->skin.normals[v], glm::normalize(posed.normals[v])), 1e-5f);
    const auto want = test::weightsByName(a, v);
    const auto got = test::weightsByName(*back, v);
    ASSERT_EQ(want.size(), got.size()) << "vertex " << v;
    for (const auto& [name, w] : want) ASSERT_NEAR(got.at(name), w, 1e-6) << "vertex " << v;
  }
  // The re-imported skeleton rests in the posed posture.
  const std::vector<glm::mat4> rest = restModelTransforms(back->skeleton);
  for (std::size_t j = 0; j < rest.size(); ++j) {
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r)
        ASSERT_NEAR(rest[j][c][r], posed.model[j][c][r], 1e-5f) << a.skeleton.names[j];
    }
  }
}

TEST(GltfExport, PosedChainRoundTripsLbsAndDqs) {
  const AvatarModel a = chainAvatar();
  expectRoundTrip(a, bentPosture(a.skeleton, 0.5f), SkinningMethod::kLinear);
  expectRoundTrip(a, bentPosture(a.skeleton, 0.9f), SkinningMethod::kDualQuaternion);
  expectRoundTrip(a, restPosture(a.skeleton), SkinningMethod::kLinear);
}

TEST(GltfExport, PosedSharedAvatarRoundTrips) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  Result<AvatarModel> a = importGltfAvatar(path);
  ASSERT_TRUE(a.ok()) << a.error().message;
  expectRoundTrip(*a, bentPosture(a->skeleton, 0.3f), SkinningMethod::kLinear);
}

TEST(GltfExport, AccessorBoundsAreExactAndLayoutIsAsDocumented) {
  const AvatarModel a = chainAvatar();
  Result<std::vector<std::uint8_t>> bytes = encodeGlb(restAvatarScene(a));
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  const nlohmann::json doc = glbJson(*bytes);
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  EXPECT_EQ(doc["nodes"][0]["mesh"], 0);
  EXPECT_EQ(doc["nodes"][0]["skin"], 0);
  EXPECT_EQ(doc["nodes"].size(), a.skeleton.names.size() + 1);
  EXPECT_EQ(doc["nodes"][1]["name"], a.skeleton.names[0]);
  EXPECT_EQ(doc["skins"][0]["joints"].size(), a.skeleton.names.size());
  const nlohmann::json& attributes = doc["meshes"][0]["primitives"][0]["attributes"];
  EXPECT_TRUE(attributes.contains("JOINTS_1"));  // the chain has 8 influences
  const nlohmann::json& acc = doc["accessors"][attributes["POSITION"].get<std::size_t>()];
  const Bounds box = computeBounds(a.skin.positions);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(acc["min"][static_cast<std::size_t>(c)].get<float>(), box.min[c]);
    EXPECT_EQ(acc["max"][static_cast<std::size_t>(c)].get<float>(), box.max[c]);
  }
  for (const auto& view : doc["bufferViews"])
    EXPECT_EQ(view["byteOffset"].get<std::size_t>() % 4, 0u);
}

TEST(GltfExport, VertexAnimationAsMorphTargets) {
  const AvatarModel a = chainAvatar();
  GltfScene scene = restAvatarScene(a);
  scene.skin.reset();  // a plain animated mesh
  const int frames = 12;
  for (int f = 0; f < frames; ++f) {
    const Posed posed = pose(a, bentPosture(a.skeleton, 0.05f * f), SkinningMethod::kLinear);
    scene.frames.push_back({posed.positions, posed.normals});
  }
  scene.frame_time = 0.04;
  Result<std::vector<std::uint8_t>> bytes = encodeGlb(scene);
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  const nlohmann::json doc = glbJson(*bytes);
  const nlohmann::json& prim = doc["meshes"][0]["primitives"][0];
  ASSERT_EQ(prim["targets"].size(), static_cast<std::size_t>(frames));
  EXPECT_TRUE(prim["targets"][0].contains("NORMAL"));
  EXPECT_EQ(doc["meshes"][0]["weights"].size(), static_cast<std::size_t>(frames));
  const nlohmann::json& sampler = doc["animations"][0]["samplers"][0];
  EXPECT_EQ(sampler["interpolation"], "STEP");
  const nlohmann::json& input = doc["accessors"][sampler["input"].get<std::size_t>()];
  EXPECT_EQ(input["count"], frames);
  EXPECT_NEAR(input["max"][0].get<double>(), 0.04 * (frames - 1), 1e-6);
  EXPECT_EQ(doc["accessors"][sampler["output"].get<std::size_t>()]["count"], frames * frames);
  EXPECT_EQ(doc["animations"][0]["channels"][0]["target"]["path"], "weights");
  EXPECT_FALSE(doc.contains("skins"));
}

TEST(GltfExport, BadScenesAreRefused) {
  const AvatarModel a = chainAvatar();
  GltfScene scene = restAvatarScene(a);
  scene.mesh.indices.push_back(0);
  EXPECT_FALSE(encodeGlb(scene).ok());

  scene = restAvatarScene(a);
  scene.mesh.indices[4] = 1000000;
  Result<std::vector<std::uint8_t>> r = encodeGlb(scene);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("triangle 1 refers to vertex 1000000"), std::string::npos);

  scene = restAvatarScene(a);
  std::fill(scene.skin->weights.begin(), scene.skin->weights.begin() + scene.skin->influences,
            0.0f);
  r = encodeGlb(scene);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("vertex 0 has no weight"), std::string::npos);

  scene = restAvatarScene(a);
  scene.skin->parents[2] = 5;
  EXPECT_FALSE(encodeGlb(scene).ok());

  scene = restAvatarScene(a);
  scene.frames.push_back({std::vector<glm::vec3>(3), {}});
  EXPECT_FALSE(encodeGlb(scene).ok());

  scene = restAvatarScene(a);
  scene.mesh.positions[0].x = std::nanf("");
  EXPECT_FALSE(encodeGlb(scene).ok());

  EXPECT_FALSE(writeGlb(test::scratchDir() + "/no/such/folder/x.glb", restAvatarScene(a)).ok());
}

TEST(GltfExport, UnnormalisedWeightsAreNormalisedOnWriting) {
  const AvatarModel a = chainAvatar();
  GltfScene scene = restAvatarScene(a);
  for (float& w : scene.skin->weights) w *= 3.0f;
  Result<std::vector<std::uint8_t>> bytes = encodeGlb(scene);
  ASSERT_TRUE(bytes.ok());
  Result<AvatarModel> back = importGltfAvatarFromMemory(*bytes, "w.glb");
  ASSERT_TRUE(back.ok()) << back.error().message;
  for (std::size_t v = 0; v < a.skin.positions.size(); ++v) {
    const auto want = test::weightsByName(a, v);
    for (const auto& [name, w] : test::weightsByName(*back, v)) EXPECT_NEAR(w, want.at(name), 1e-6);
  }
}

}  // namespace
}  // namespace vistel
