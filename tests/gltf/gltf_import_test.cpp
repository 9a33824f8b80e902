#include "offline/gltf/gltf_import.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

double maxDifference(const glm::mat4& a, const glm::dmat4& b) {
  double d = 0.0;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(static_cast<double>(a[c][r]) - b[c][r]));
  }
  return d;
}

// Compares an imported chain with the answers makeChainGltf computed.
void expectChain(const AvatarModel& avatar, const test::ChainGltf& chain, double tol = 2e-6) {
  ASSERT_TRUE(validateAvatar(avatar).ok()) << validateAvatar(avatar).error().message;
  ASSERT_EQ(avatar.skin.positions.size(), chain.positions_model.size());
  EXPECT_EQ(avatar.skin.triangleCount(), chain.triangles);
  for (std::size_t v = 0; v < chain.positions_model.size(); ++v) {
    const glm::dvec3 got(avatar.skin.positions[v]);
    ASSERT_LT(glm::distance(got, chain.positions_model[v]), tol) << "vertex " << v;
  }

  // Joints: same names, parents first, rigid model frames as expected.
  ASSERT_EQ(avatar.skeleton.jointCount(), static_cast<int>(chain.names.size()));
  const std::vector<glm::mat4> model = restModelTransforms(avatar.skeleton);
  for (std::size_t j = 0; j < chain.names.size(); ++j) {
    const int i = avatar.skeleton.find(chain.names[j]);
    ASSERT_GE(i, 0) << chain.names[j];
    EXPECT_LT(maxDifference(model[static_cast<std::size_t>(i)], chain.joint_model[j]), 2e-6)
        << chain.names[j];
    if (j > 0) {
      EXPECT_EQ(avatar.skeleton.parents[static_cast<std::size_t>(i)],
                avatar.skeleton.find(chain.names[j - 1]));
    }
  }
  EXPECT_EQ(avatar.skeleton.names[0], chain.names[0]);

  // Weights by joint name, normalised.
  for (std::size_t v = 0; v < chain.weights.size(); ++v) {
    if (chain.weights[v].empty()) continue;
    const auto got = test::weightsByName(avatar, v);
    ASSERT_EQ(got.size(), chain.weights[v].size()) << "vertex " << v;
    for (const auto& [name, w] : chain.weights[v]) {
      ASSERT_TRUE(got.count(name)) << "vertex " << v << " lacks " << name;
      EXPECT_NEAR(got.at(name), w, 1e-6) << "vertex " << v << " joint " << name;
    }
  }
}

TEST(GltfImport, SharedMakeHumanAvatar) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  GltfImportReport report;
  Result<AvatarModel> avatar = importGltfAvatar(path, {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  const AvatarModel& a = *avatar;
  EXPECT_EQ(a.name, "makehuman_game_engine");
  EXPECT_EQ(a.skin.vertexCount(), 13380);
  EXPECT_EQ(a.skin.triangleCount(), 26756);
  ASSERT_EQ(a.skeleton.jointCount(), 53);
  EXPECT_TRUE(validateAvatar(a).ok());
  EXPECT_FALSE(report.rest_from_inverse_bind);
  EXPECT_FALSE(report.synthetic_root);
  EXPECT_FALSE(report.normals_computed);
  EXPECT_EQ(report.unweighted_vertices, 0);

  // Joint names and hierarchy.
  EXPECT_EQ(a.skeleton.names[0], "Root");
  EXPECT_EQ(a.skeleton.names[1], "pelvis");
  for (const char* name : {"spine_01", "spine_02", "spine_03", "neck_01", "head", "clavicle_l",
                           "upperarm_l", "lowerarm_l", "hand_l", "thumb_01_l", "index_03_r",
                           "pinky_02_r", "thigh_l", "calf_r", "foot_l", "ball_r"}) {
    EXPECT_GE(a.skeleton.find(name), 0) << name;
  }
  EXPECT_EQ(a.skeleton.parents[static_cast<std::size_t>(a.skeleton.find("lowerarm_l"))],
            a.skeleton.find("upperarm_l"));
  EXPECT_EQ(a.skeleton.parents[static_cast<std::size_t>(a.skeleton.find("pelvis"))], 0);

  // Weights: at most 4, each vertex sums to 1.
  EXPECT_LE(maxInfluencesUsed(a.skin), 4);
  EXPECT_GE(maxInfluencesUsed(a.skin), 2);
  const auto k = static_cast<std::size_t>(a.skin.influences);
  for (std::size_t v = 0; v < a.skin.positions.size(); ++v) {
    float sum = 0.0f;
    for (std::size_t s = 0; s < k; ++s) sum += a.skin.weights[v * k + s];
    ASSERT_NEAR(sum, 1.0f, 1e-5f) << "vertex " << v;
    ASSERT_NEAR(glm::length(a.skin.normals[v]), 1.0f, 1e-4f) << "vertex " << v;
  }

  // Bounds: metres, +Y up, about 1.67 m tall, narrower front to back than side to side.
  const Bounds box = computeBounds(a.skin.positions);
  const glm::vec3 size = box.max - box.min;
  EXPECT_NEAR(size.y, 1.666f, 0.03f);
  EXPECT_GT(size.y, size.x);
  EXPECT_GT(size.x, size.z);

  // The rest posture reproduces the mesh (rest = bind).
  std::vector<glm::mat4> model(53), skin(53);
  poseSkeleton(a.skeleton, restPosture(a.skeleton), model);
  skinningMatrices(a.skeleton, model, skin);
  std::vector<glm::vec3> pos(a.skin.positions.size()), nrm(pos.size());
  std::vector<DualQuat> dq(53);
  skinMesh(a.skin, SkinningMethod::kLinear, skin, dq, pos, nrm);
  for (std::size_t v = 0; v < pos.size(); ++v) {
    ASSERT_LT(glm::distance(pos[v], a.skin.positions[v]), 1e-5f) << "vertex " << v;
  }
}

TEST(GltfImport, ZUpCentimetreChainWithEightInfluencesAndNoNormals) {
  const test::ChainGltf chain = test::makeChainGltf();
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "chain.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  expectChain(*avatar, chain);
  EXPECT_EQ(avatar->name, "chain");
  EXPECT_EQ(avatar->skin.influences, 8);
  EXPECT_EQ(maxInfluencesUsed(avatar->skin), 8);
  EXPECT_FALSE(report.rest_from_inverse_bind);
  EXPECT_TRUE(report.normals_computed);
  EXPECT_EQ(report.boundary_edges, 0);
  EXPECT_EQ(report.non_manifold_vertices, 0);

  // Computed normals: unit and outward; the closed column has positive volume.
  for (std::size_t v = 0; v < chain.radial_model.size(); ++v) {
    const glm::dvec3 n(avatar->skin.normals[v]);
    EXPECT_NEAR(glm::length(n), 1.0, 1e-5);
    EXPECT_GT(glm::dot(n, chain.radial_model[v]), 0.5) << "vertex " << v;
  }
  EXPECT_GT(enclosedVolume(avatar->skin.positions, avatar->skin.indices), 0.0);

  // Model space: metres, +Y up (the column stands 0.5 .. 1.58 m high).
  const Bounds box = computeBounds(avatar->skin.positions);
  EXPECT_NEAR(box.min.y, 0.5f, 1e-5f);
  EXPECT_NEAR(box.max.y, 0.5f + 0.12f * 9, 1e-5f);
}

TEST(GltfImport, FileNormalsAreCarriedIntoModelSpace) {
  test::ChainOptions opt;
  opt.normals = true;
  const test::ChainGltf chain = test::makeChainGltf(opt);
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "chain.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_FALSE(report.normals_computed);
  for (std::size_t v = 0; v < chain.normals_model.size(); ++v) {
    EXPECT_LT(glm::distance(glm::dvec3(avatar->skin.normals[v]), chain.normals_model[v]), 1e-6);
  }
}

TEST(GltfImport, WorldSpaceBindMatricesGiveTheSameModel) {
  test::ChainOptions opt;
  opt.mesh_space_ibm = false;  // mesh node at the root, vertices already in metres
  opt.scramble_skin_order = false;
  const test::ChainGltf chain = test::makeChainGltf(opt);
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "chain.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  expectChain(*avatar, chain);
}

TEST(GltfImport, IndexTypesAndNoIndices) {
  for (int component : {5121, 5123, 5125, 0}) {
    test::ChainOptions opt;
    opt.index_component = component;
    opt.eight_influences = component != 5121;
    const test::ChainGltf chain = test::makeChainGltf(opt);
    Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "chain.glb");
    ASSERT_TRUE(avatar.ok()) << component << ": " << avatar.error().message;
    expectChain(*avatar, chain);
    EXPECT_EQ(avatar->skin.influences, opt.eight_influences ? 8 : 4);
  }
}

TEST(GltfImport, TextGltfWithExternalAndEmbeddedBuffers) {
  const test::ChainGltf chain = test::makeChainGltf();
  const std::string dir = test::scratchDir();
  const std::string path = chain.file.writeGltfWithBin(dir, "chain");
  Result<AvatarModel> external = importGltfAvatar(path);
  ASSERT_TRUE(external.ok()) << external.error().message;
  expectChain(*external, chain);

  const std::string text = chain.file.gltfEmbedded();
  const std::vector<std::uint8_t> bytes(text.begin(), text.end());
  Result<AvatarModel> embedded = importGltfAvatarFromMemory(bytes, "chain.gltf");
  ASSERT_TRUE(embedded.ok()) << embedded.error().message;
  expectChain(*embedded, chain);

  // A missing external buffer is an error naming the file.
  std::filesystem::remove(dir + "/chain.bin");
  Result<AvatarModel> missing = importGltfAvatar(path);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("chain.gltf"), std::string::npos)
      << missing.error().message;
}

TEST(GltfImport, RestThatDisagreesWithTheBindMatricesIsReplacedByTheBind) {
  test::ChainGltf chain = test::makeChainGltf();
  // Bend joint j5 in the node hierarchy only (the IBMs still hold the bind posture).
  auto& node = chain.file.doc["nodes"][static_cast<std::size_t>(chain.joint_nodes[5])];
  node["rotation"] = {0.3826834, 0.0, 0.0, 0.9238795};
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "bent.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_TRUE(report.rest_from_inverse_bind);
  EXPECT_TRUE(test::hasWarning(report, "disagree"))
      << (report.warnings.empty() ? "" : report.warnings[0]);
  expectChain(*avatar, chain, 5e-6);
}

TEST(GltfImport, SeveralRootsGetASyntheticRoot) {
  test::ChainGltf chain = test::makeChainGltf();
  // Detach j6 (and its descendants) from j5: make it a child of the conversion node.
  auto& nodes = chain.file.doc["nodes"];
  const int j5 = chain.joint_nodes[5], j6 = chain.joint_nodes[6];
  nodes[static_cast<std::size_t>(j5)].erase("children");
  nodes[0]["children"].push_back(j6);
  // j6's world frame is unchanged only if its local becomes its file-space world frame:
  // recompute it from the expected model frame (conv^-1 * model, scale 100).
  const glm::dmat4 conv_inv =
      glm::inverse(glm::rotate(glm::dmat4(1.0), -glm::half_pi<double>(), {1, 0, 0}) *
                   glm::scale(glm::dmat4(1.0), glm::dvec3(0.01)));
  glm::dmat4 local = conv_inv * chain.joint_model[6];
  for (int c = 0; c < 3; ++c) local[c] = glm::normalize(local[c]);
  const nlohmann::json trs = test::trsOf(local);
  nodes[static_cast<std::size_t>(j6)]["translation"] = trs["translation"];
  nodes[static_cast<std::size_t>(j6)]["rotation"] = trs["rotation"];

  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "roots.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_TRUE(report.synthetic_root);
  EXPECT_FALSE(report.rest_from_inverse_bind);
  const Skeleton& s = avatar->skeleton;
  ASSERT_EQ(s.jointCount(), 11);
  EXPECT_EQ(s.names[0], "root");
  EXPECT_EQ(s.parents[static_cast<std::size_t>(s.find("j0"))], 0);
  EXPECT_EQ(s.parents[static_cast<std::size_t>(s.find("j6"))], 0);
  EXPECT_EQ(s.parents[static_cast<std::size_t>(s.find("j7"))], s.find("j6"));
  const std::vector<glm::mat4> model = restModelTransforms(s);
  EXPECT_LT(maxDifference(model[static_cast<std::size_t>(s.find("j6"))], chain.joint_model[6]),
            2e-6);
}

TEST(GltfImport, UnweightedVerticesAreBoundWithAWarning) {
  test::ChainOptions opt;
  opt.unweighted = {0, 5, 40};
  const test::ChainGltf chain = test::makeChainGltf(opt);
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "chain.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_EQ(report.unweighted_vertices, 3);
  EXPECT_TRUE(test::hasWarning(report, "zero total weight"));
  // The mesh node is not under a joint: each goes to its nearest joint, fully.
  for (int v : opt.unweighted) {
    const auto w = test::weightsByName(*avatar, static_cast<std::size_t>(v));
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w.begin()->second, 1.0);
  }
  EXPECT_EQ(test::weightsByName(*avatar, 0).begin()->first, "j0");
}

TEST(GltfImport, PrimitivesSharingVerticesAreMergedOnce) {
  test::ChainGltf chain = test::makeChainGltf();
  auto& mesh = chain.file.doc["meshes"][0];
  mesh["primitives"].push_back(mesh["primitives"][0]);  // same attributes, same triangles
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "twice.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_EQ(avatar->skin.positions.size(), chain.positions_model.size());
  EXPECT_EQ(avatar->skin.triangleCount(), 2 * chain.triangles);
}

TEST(GltfImport, NonTriangleModesAreRefused) {
  test::ChainGltf chain = test::makeChainGltf();
  chain.file.doc["meshes"][0]["primitives"][0]["mode"] = 5;
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "strip.glb");
  ASSERT_FALSE(avatar.ok());
  EXPECT_NE(avatar.error().message.find("strip.glb: mesh 0 primitive 0: mode 5"), std::string::npos)
      << avatar.error().message;
}

TEST(GltfImport, RecomputeNormalsOption) {
  test::ChainOptions opt;
  opt.normals = true;
  const test::ChainGltf chain = test::makeChainGltf(opt);
  GltfImportOptions options;
  options.recompute_normals = true;
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "c.glb", "", options, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_TRUE(report.normals_computed);
}

}  // namespace
}  // namespace vistel

namespace vistel {
namespace {

// The float values of an accessor that the builder wrote (tightly packed).
std::vector<float> floatsOf(const test::GltfBuilder& b, int accessor) {
  const auto& acc = b.doc["accessors"][static_cast<std::size_t>(accessor)];
  const auto& view = b.doc["bufferViews"][acc["bufferView"].get<std::size_t>()];
  std::vector<float> out(view["byteLength"].get<std::size_t>() / 4);
  std::memcpy(out.data(), b.bin.data() + view["byteOffset"].get<std::size_t>(), out.size() * 4);
  return out;
}

TEST(GltfImport, InterleavedAttributes) {
  test::ChainOptions opt;
  opt.normals = true;
  test::ChainGltf chain = test::makeChainGltf(opt);
  auto& attributes = chain.file.doc["meshes"][0]["primitives"][0]["attributes"];
  const std::vector<float> pos = floatsOf(chain.file, attributes["POSITION"]);
  const std::vector<float> nrm = floatsOf(chain.file, attributes["NORMAL"]);
  std::vector<float> both;
  for (std::size_t v = 0; v < pos.size() / 3; ++v) {
    both.insert(both.end(), pos.begin() + 3 * v, pos.begin() + 3 * v + 3);
    both.insert(both.end(), nrm.begin() + 3 * v, nrm.begin() + 3 * v + 3);
  }
  const int view = chain.file.addView(both.data(), both.size() * 4, 24);
  const std::size_t count = pos.size() / 3;
  auto& accessors = chain.file.doc["accessors"];
  accessors.push_back(
      {{"bufferView", view}, {"componentType", 5126}, {"count", count}, {"type", "VEC3"}});
  attributes["POSITION"] = accessors.size() - 1;
  accessors.push_back({{"bufferView", view},
                       {"byteOffset", 12},
                       {"componentType", 5126},
                       {"count", count},
                       {"type", "VEC3"}});
  attributes["NORMAL"] = accessors.size() - 1;
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "interleaved.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  expectChain(*avatar, chain);
  for (std::size_t v = 0; v < chain.normals_model.size(); ++v) {
    EXPECT_LT(glm::distance(glm::dvec3(avatar->skin.normals[v]), chain.normals_model[v]), 1e-6);
  }
}

TEST(GltfImport, SparseAccessorSubstitution) {
  test::ChainGltf chain = test::makeChainGltf();
  auto& attributes = chain.file.doc["meshes"][0]["primitives"][0]["attributes"];
  std::vector<float> pos = floatsOf(chain.file, attributes["POSITION"]);
  const std::vector<std::uint16_t> targets = {3, 17, 50};
  std::vector<float> values;
  for (std::uint16_t t : targets) {
    values.insert(values.end(), pos.begin() + 3 * t, pos.begin() + 3 * t + 3);
    std::fill(pos.begin() + 3 * t, pos.begin() + 3 * t + 3, 0.0f);  // wrong in the dense data
  }
  const int dense = chain.file.addView(pos.data(), pos.size() * 4);
  const int idx_view = chain.file.addView(targets.data(), targets.size() * 2);
  const int val_view = chain.file.addView(values.data(), values.size() * 4);
  auto& accessors = chain.file.doc["accessors"];
  accessors.push_back({{"bufferView", dense},
                       {"componentType", 5126},
                       {"count", pos.size() / 3},
                       {"type", "VEC3"},
                       {"sparse",
                        {{"count", targets.size()},
                         {"indices", {{"bufferView", idx_view}, {"componentType", 5123}}},
                         {"values", {{"bufferView", val_view}}}}}});
  attributes["POSITION"] = accessors.size() - 1;
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(chain.file.glb(), "sparse.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  expectChain(*avatar, chain);

  // Sparse indices out of order are refused.
  std::swap(
      chain.file.bin[chain.file.doc["bufferViews"][static_cast<std::size_t>(idx_view)]["byteOffset"]
                         .get<std::size_t>()],
      chain.file.bin[chain.file.doc["bufferViews"][static_cast<std::size_t>(idx_view)]["byteOffset"]
                         .get<std::size_t>() +
                     2]);
  Result<AvatarModel> bad = importGltfAvatarFromMemory(chain.file.glb(), "sparse.glb");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("not increasing"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace vistel

namespace vistel {
namespace {

TEST(GltfImport, MissingInverseBindMatricesMeanIdentity) {
  // Without IBMs the spec's bind posture has every joint at the mesh's origin frame; the
  // vertices are where the mesh node's space puts them.
  test::ChainGltf chain = test::makeChainGltf();
  chain.file.doc["skins"][0].erase("inverseBindMatrices");
  GltfImportReport report;
  Result<AvatarModel> avatar =
      importGltfAvatarFromMemory(chain.file.glb(), "noibm.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_TRUE(report.rest_from_inverse_bind);
  for (std::size_t v = 0; v < chain.positions_model.size(); ++v) {
    ASSERT_LT(glm::distance(glm::dvec3(avatar->skin.positions[v]), chain.positions_model[v]), 2e-6);
  }
  for (const glm::mat4& m : restModelTransforms(avatar->skeleton)) {
    EXPECT_LT(glm::length(glm::vec3(m[3])), 1e-6f);
  }
}

}  // namespace
}  // namespace vistel
