// Exported .glb files under the Khronos glTF validator: 0 errors (skipped when node/npm
// or the validator are unavailable).
#include <gtest/gtest.h>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/glb/gltf_export.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

AvatarModel chainAvatar() {
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(test::makeChainGltf().file.glb(), "chain.glb");
  EXPECT_TRUE(avatar.ok()) << avatar.error().message;
  return std::move(*avatar);
}

Posture bent(const Skeleton& s, float amount) {
  Posture p = restPosture(s);
  for (std::size_t j = 0; j < p.rotations.size(); ++j) {
    const glm::vec3 axis = glm::normalize(glm::vec3(std::cos(2.1f * j), 0.5f, std::sin(0.9f * j)));
    p.rotations[j] = glm::normalize(p.rotations[j] * glm::angleAxis(amount, axis));
  }
  return p;
}

// Model transforms, positions and normals of a skinned posture.
void skin(const AvatarModel& a, const Posture& p, SkinningMethod method,
          std::vector<glm::mat4>& model, std::vector<glm::vec3>& pos, std::vector<glm::vec3>& nrm) {
  const std::size_t nj = a.skeleton.names.size();
  model.resize(nj);
  std::vector<glm::mat4> m(nj);
  std::vector<DualQuat> dq(nj);
  pos.resize(a.skin.positions.size());
  nrm.resize(pos.size());
  poseSkeleton(a.skeleton, p, model);
  skinningMatrices(a.skeleton, model, m);
  skinMesh(a.skin, method, m, dq, pos, nrm);
}

void expectValid(const std::string& path) {
  VISTEL_VALIDATE_OR_SKIP(verdict, path);
  EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
}

TEST(GltfValidator, RestAvatarWithEightInfluences) {
  const std::string path = test::scratchDir() + "/rest.glb";
  ASSERT_TRUE(writeGlb(path, restAvatarScene(chainAvatar())).ok());
  expectValid(path);
}

TEST(GltfValidator, PosedAvatarLbs) {
  const AvatarModel a = chainAvatar();
  std::vector<glm::mat4> model;
  std::vector<glm::vec3> pos, nrm;
  skin(a, bent(a.skeleton, 0.6f), SkinningMethod::kLinear, model, pos, nrm);
  const std::string path = test::scratchDir() + "/lbs.glb";
  ASSERT_TRUE(writeGlb(path, posedAvatarScene(a, model, pos, nrm)).ok());
  expectValid(path);
}

TEST(GltfValidator, PosedAvatarDqs) {
  const AvatarModel a = chainAvatar();
  std::vector<glm::mat4> model;
  std::vector<glm::vec3> pos, nrm;
  skin(a, bent(a.skeleton, 1.1f), SkinningMethod::kDualQuaternion, model, pos, nrm);
  const std::string path = test::scratchDir() + "/dqs.glb";
  ASSERT_TRUE(writeGlb(path, posedAvatarScene(a, model, pos, nrm)).ok());
  expectValid(path);
}

TEST(GltfValidator, MultiFrameAnimationSkinnedAndPlain) {
  const AvatarModel a = chainAvatar();
  GltfScene scene = restAvatarScene(a);
  std::vector<glm::mat4> model;
  std::vector<glm::vec3> pos, nrm;
  for (int f = 0; f < 24; ++f) {
    skin(a, bent(a.skeleton, 0.05f * f), SkinningMethod::kDualQuaternion, model, pos, nrm);
    scene.frames.push_back({pos, nrm});
  }
  const std::string dir = test::scratchDir();
  ASSERT_TRUE(writeGlb(dir + "/skinned_frames.glb", scene).ok());
  expectValid(dir + "/skinned_frames.glb");

  scene.skin.reset();
  for (GltfFrame& frame : scene.frames) frame.normals.clear();
  ASSERT_TRUE(writeGlb(dir + "/plain_frames.glb", scene).ok());
  expectValid(dir + "/plain_frames.glb");
}

TEST(GltfValidator, SharedAvatarReexportedAtRest) {
  VISTEL_REQUIRE_SHARED(source, "avatars/makehuman_game_engine.glb");
  Result<AvatarModel> a = importGltfAvatar(source);
  ASSERT_TRUE(a.ok()) << a.error().message;
  const std::string path = test::scratchDir() + "/makehuman_rest.glb";
  ASSERT_TRUE(writeGlb(path, restAvatarScene(*a)).ok());
  expectValid(path);
}

}  // namespace
}  // namespace vistel
