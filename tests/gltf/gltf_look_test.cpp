// glTF import and export of the look (texture coordinates, materials, textures), texture
// downscaling to the avatar size limit, and VRM humanoid import.
#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/glb/gltf_export.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/gltf/gltf_look.hpp"
#include "offline/gltf/gltf_vrm.hpp"
#include "tests/gltf/gltf_look_models.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

std::vector<std::uint8_t> halvesPng() {
  return test::makePng(16, 8, [](int x, int) {
    return x < 8 ? glm::u8vec4(220, 30, 20, 255) : glm::u8vec4(20, 40, 230, 255);
  });
}

Result<std::vector<std::uint8_t>> boxGlb() {
  return encodeGlb(test::texturedBoxScene(halvesPng()));
}

TEST(GltfLook, ImportKeepsUvsMaterialAndTexture) {
  auto glb = boxGlb();
  ASSERT_TRUE(glb.ok()) << glb.error().message;
  GltfImportReport report;
  auto avatar = importGltfAvatarFromMemory(*glb, "box.glb", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  const AvatarLook& look = avatar->look;
  const GltfScene scene = test::texturedBoxScene(halvesPng());
  EXPECT_EQ(look.uvs, scene.look.uvs);
  ASSERT_EQ(look.materials.size(), 1u);
  EXPECT_EQ(look.materials[0].name, "box");
  EXPECT_EQ(look.materials[0].base_color_texture, 0);
  EXPECT_EQ(look.materials[0].normal_texture, -1);
  ASSERT_EQ(look.textures.size(), 1u);
  EXPECT_EQ(look.textures[0].mime, "image/png");
  EXPECT_EQ(look.textures[0].width, 16);
  EXPECT_EQ(look.textures[0].height, 8);
  EXPECT_EQ(look.textures[0].encoded, halvesPng());
  EXPECT_EQ(report.materials, 1);
  EXPECT_EQ(report.textures, 1);
  EXPECT_EQ(report.textures_downscaled, 0);
  // Through the .vavatar and back.
  auto decoded = decodeAvatar(encodeAvatar(*avatar), "box.vavatar");
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->look.textures[0].encoded, halvesPng());
  EXPECT_EQ(decoded->look.uvs, look.uvs);
  // Geometry only, when asked.
  GltfImportOptions plain;
  plain.import_look = false;
  auto bare = importGltfAvatarFromMemory(*glb, "box.glb", "", plain);
  ASSERT_TRUE(bare.ok());
  EXPECT_TRUE(bare->look.empty());
}

TEST(GltfLook, SubmeshesAndNormalMapsRoundTripThroughExport) {
  GltfScene scene = test::texturedBoxScene(halvesPng(), glm::vec4(0.5f, 0.75f, 1.0f, 1.0f));
  // A second material with a normal map on the last two faces (12 indices).
  AvatarTexture normal;
  normal.name = "bumps";
  normal.mime = "image/png";
  normal.encoded = test::makePng(4, 4, [](int x, int y) {
    return glm::u8vec4(128 + 20 * (x % 2), 128 + 20 * (y % 2), 250, 255);
  });
  normal.width = normal.height = 4;
  scene.look.textures.push_back(normal);
  AvatarMaterial second;
  second.name = "cap";
  second.base_color = {0.2f, 0.2f, 0.2f, 1.0f};
  second.normal_texture = 1;
  second.normal_scale = 0.5f;
  second.double_sided = true;
  scene.look.materials.push_back(second);
  scene.look.submeshes = {{0, 24, 0}, {24, 12, 1}};
  auto glb = encodeGlb(scene);
  ASSERT_TRUE(glb.ok()) << glb.error().message;
  auto avatar = importGltfAvatarFromMemory(*glb, "box2.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  const AvatarLook& look = avatar->look;
  ASSERT_EQ(look.materials.size(), 2u);
  ASSERT_EQ(look.submeshes.size(), 2u);
  EXPECT_EQ(look.submeshes[0].index_count, 24u);
  EXPECT_EQ(look.submeshes[1].first_index, 24u);
  EXPECT_EQ(look.submeshes[1].material, 1);
  EXPECT_EQ(look.materials[1].normal_texture, 1);
  EXPECT_FLOAT_EQ(look.materials[1].normal_scale, 0.5f);
  EXPECT_TRUE(look.materials[1].double_sided);
  EXPECT_EQ(look.materials[0].base_color, glm::vec4(0.5f, 0.75f, 1.0f, 1.0f));
  EXPECT_EQ(look.textures[1].encoded, normal.encoded);
  // Export the imported avatar again: the same look comes back.
  auto again = encodeGlb(restAvatarScene(*avatar));
  ASSERT_TRUE(again.ok()) << again.error().message;
  auto second_import = importGltfAvatarFromMemory(*again, "again.glb");
  ASSERT_TRUE(second_import.ok()) << second_import.error().message;
  ASSERT_EQ(second_import->look.textures.size(), 2u);
  EXPECT_EQ(second_import->look.textures[1].encoded, normal.encoded);
  EXPECT_EQ(second_import->look.materials[1].name, "cap");
  EXPECT_EQ(second_import->look.uvs, look.uvs);
  EXPECT_EQ(second_import->look.submeshes.size(), 2u);
}

TEST(GltfLook, ExternalImageFilesAreRead) {
  const std::string dir = test::scratchDir() + "/gltf_look_external";
  std::filesystem::create_directories(dir);
  auto glb = boxGlb();
  ASSERT_TRUE(glb.ok());
  // The image as a file next to the .glb instead of a buffer view.
  const auto edited = test::editGlbJson(*glb, [](nlohmann::json& doc) {
    doc["images"][0].erase("bufferView");
    doc["images"][0].erase("mimeType");
    doc["images"][0]["uri"] = "box%20texture.png";
  });
  ASSERT_TRUE(writeFileBytes(dir + "/box texture.png", halvesPng()).ok());
  ASSERT_TRUE(writeFileBytes(dir + "/box.glb", edited).ok());
  GltfImportReport report;
  auto avatar = importGltfAvatar(dir + "/box.glb", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  ASSERT_EQ(avatar->look.textures.size(), 1u);
  EXPECT_EQ(avatar->look.textures[0].encoded, halvesPng());
  // A missing file: the texture is dropped with a warning, the avatar still imports.
  std::filesystem::remove(dir + "/box texture.png");
  GltfImportReport missing;
  auto without = importGltfAvatar(dir + "/box.glb", {}, &missing);
  ASSERT_TRUE(without.ok()) << without.error().message;
  EXPECT_TRUE(without->look.textures.empty());
  EXPECT_EQ(without->look.materials.size(), 1u);
  EXPECT_EQ(without->look.materials[0].base_color_texture, -1);
  EXPECT_TRUE(test::hasWarning(missing, "texture dropped"))
      << fmt::format("{}", fmt::join(missing.warnings, "\n"));
}

TEST(GltfLook, BadImageAndTextureReferencesAreHandled) {
  auto glb = boxGlb();
  ASSERT_TRUE(glb.ok());
  // Not a PNG or JPEG: dropped with a warning.
  const auto webp = test::editGlbJson(*glb, [](nlohmann::json& doc) {
    doc["images"][0]["mimeType"] = "image/webp";
    doc["bufferViews"][doc["images"][0]["bufferView"].get<int>()]["byteOffset"] = 0;
  });
  GltfImportReport report;
  auto a = importGltfAvatarFromMemory(webp, "webp.glb", "", {}, &report);
  ASSERT_TRUE(a.ok()) << a.error().message;
  EXPECT_TRUE(a->look.textures.empty());
  EXPECT_TRUE(test::hasWarning(report, "not PNG or JPEG"))
      << fmt::format("{}", fmt::join(report.warnings, "\n"));
  // A texture index out of range: an error naming it.
  const auto bad_texture = test::editGlbJson(*glb, [](nlohmann::json& doc) {
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 7;
  });
  auto b = importGltfAvatarFromMemory(bad_texture, "bad.glb");
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().message.find("texture 7"), std::string::npos) << b.error().message;
  // A second texture coordinate set: the texture is dropped, said why.
  const auto set1 = test::editGlbJson(*glb, [](nlohmann::json& doc) {
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1;
  });
  GltfImportReport r1;
  auto c = importGltfAvatarFromMemory(set1, "set1.glb", "", {}, &r1);
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_TRUE(test::hasWarning(r1, "TEXCOORD_1"));
  EXPECT_EQ(c->look.materials[0].base_color_texture, -1);
}

TEST(GltfLook, TexturesAreDownscaledToFitTheAvatarSizeLimit) {
  // Noise does not compress: 512 x 512 RGBA is about 1 MB of PNG.
  std::uint32_t state = 12345;
  const auto noise = test::makePng(512, 512, [&](int, int) {
    state = state * 1664525u + 1013904223u;
    return glm::u8vec4(state >> 24, state >> 16, state >> 8, 255);
  });
  ASSERT_GT(noise.size(), 800000u);
  auto glb = encodeGlb(test::texturedBoxScene(noise));
  ASSERT_TRUE(glb.ok());
  GltfImportOptions options;
  options.max_avatar_bytes = 400000;  // below 2 * implicitModelAllowance: the whole limit
  GltfImportReport report;
  auto avatar = importGltfAvatarFromMemory(*glb, "noisy.glb", "", options, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_LE(encodeAvatar(*avatar).size(), 400000u);
  EXPECT_EQ(report.textures_downscaled, 1);
  EXPECT_EQ(avatar->look.textures[0].width, 256);
  EXPECT_EQ(avatar->look.textures[0].height, 256);
  EXPECT_TRUE(test::hasWarning(report, "downscaled from 512x512 to 256x256"))
      << fmt::format("{}", fmt::join(report.warnings, "\n"));
  // The downscaled texture decodes to its stated size.
  auto image = decodeTextureImage(avatar->look.textures[0].encoded, "t");
  ASSERT_TRUE(image.ok()) << image.error().message;
  EXPECT_EQ(image->width, 256);
  // The default limit (the server's 16 MiB) leaves it alone.
  GltfImportReport untouched;
  auto big = importGltfAvatarFromMemory(*glb, "noisy.glb", "", {}, &untouched);
  ASSERT_TRUE(big.ok());
  EXPECT_EQ(untouched.textures_downscaled, 0);
  EXPECT_EQ(big->look.textures[0].encoded, noise);
}

// A VRM file made from the test humanoid: joints named like VRoid's, the humanoid
// extension mapping them.
std::vector<std::uint8_t> vrmFile(bool vrm0, int bad_node = -1) {
  std::vector<std::string> names;
  for (std::size_t j = 0; j < test::humanoidCanonicalNames().size(); ++j) {
    names.push_back(fmt::format("J_Bip_{:02}", j));
  }
  auto glb = encodeGlb(test::humanoidScene(names, vrm0));
  EXPECT_TRUE(glb.ok());
  return test::editGlbJson(*glb, [&](nlohmann::json& doc) {
    const auto& bones = test::humanoidVrmBones();
    if (vrm0) {
      nlohmann::json list = nlohmann::json::array();
      for (std::size_t j = 0; j < bones.size(); ++j) {
        list.push_back({{"bone", bones[j]}, {"node", static_cast<int>(j) + 1}});
      }
      list.push_back({{"bone", "jaw"}, {"node", 0}});  // no vistel joint: ignored
      if (bad_node >= 0) list[0]["node"] = bad_node;
      doc["extensionsUsed"] = {"VRM"};
      doc["extensions"]["VRM"] = {{"exporterVersion", "test"},
                                  {"humanoid", {{"humanBones", list}}}};
    } else {
      nlohmann::json map = nlohmann::json::object();
      for (std::size_t j = 0; j < bones.size(); ++j) {
        map[bones[j]] = {{"node", static_cast<int>(j) + 1}};
      }
      if (bad_node >= 0) map["hips"]["node"] = bad_node;
      doc["extensionsUsed"] = {"VRMC_vrm"};
      doc["extensions"]["VRMC_vrm"] = {{"specVersion", "1.0"}, {"humanoid", {{"humanBones", map}}}};
    }
  });
}

TEST(GltfVrm, Vrm1HumanoidBonesBecomeCanonicalJoints) {
  GltfImportReport report;
  auto avatar = importGltfAvatarFromMemory(vrmFile(false), "avatar.vrm", "", {}, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_EQ(report.vrm_version, "1.0");
  ASSERT_TRUE(report.humanoid.has_value());
  EXPECT_EQ(report.humanoid->canonical.size(), test::humanoidCanonicalNames().size());
  for (const std::string& c : test::humanoidCanonicalNames()) {
    EXPECT_GE(avatar->skeleton.find(c), 0) << c;
  }
  // The explicit map drives the joint mapping: every entry from the VRM map.
  auto choice = explicitJointMap(*report.humanoid, avatar->skeleton);
  ASSERT_TRUE(choice.ok()) << choice.error().message;
  EXPECT_EQ(choice->map.jointFor("l_hand"), "l_hand");
  EXPECT_EQ(choice->origin[0], "vrm-humanoid");
  // Renamed, the joints are found by the ordinary mapping too (config maps, else inference).
  auto maps = loadJointMaps();
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  auto chosen = chooseJointMap(*maps, avatar->skeleton);
  ASSERT_TRUE(chosen.ok()) << chosen.error().message;
  EXPECT_EQ(chosen->map.jointFor("l_forearm"), "l_forearm");
  EXPECT_EQ(chosen->map.jointFor("r_thigh"), "r_thigh");
  // The left hand is on +X (VRM 1.0 faces +Z like vistel).
  const auto rest = restModelTransforms(avatar->skeleton);
  EXPECT_GT(rest[static_cast<std::size_t>(avatar->skeleton.find("l_hand"))][3].x, 0.5f);
}

TEST(GltfVrm, Vrm0IsTurnedToFacePlusZAndItsNamesCanBeKept) {
  GltfImportOptions keep;
  keep.vrm_canonical_names = false;
  GltfImportReport report;
  auto avatar = importGltfAvatarFromMemory(vrmFile(true), "old.vrm", "", keep, &report);
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_EQ(report.vrm_version, "0.x");
  EXPECT_TRUE(test::hasWarning(report, "jaw"));
  ASSERT_TRUE(report.humanoid.has_value());
  EXPECT_EQ(report.humanoid->jointFor("hips"), "J_Bip_00");
  EXPECT_EQ(report.humanoid->jointFor("r_foot"), "J_Bip_16");
  auto choice = explicitJointMap(*report.humanoid, avatar->skeleton);
  ASSERT_TRUE(choice.ok()) << choice.error().message;
  EXPECT_EQ(choice->map.jointFor("l_forearm"), "J_Bip_06");
  // Facing -Z in the file, the left arm was at -X; turned, it is at +X.
  const auto rest = restModelTransforms(avatar->skeleton);
  EXPECT_GT(rest[static_cast<std::size_t>(avatar->skeleton.find("J_Bip_07"))][3].x, 0.5f);
  for (const glm::vec3& p : avatar->skin.positions) EXPECT_LT(std::abs(p.z), 0.1f);
  EXPECT_TRUE(validateAvatar(*avatar).ok());
}

TEST(GltfVrm, BadHumanoidsAreRefusedNamingTheBone) {
  auto a = importGltfAvatarFromMemory(vrmFile(false, 99), "bad.vrm");
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.error().message.find("'hips': node 99"), std::string::npos) << a.error().message;
  auto b = importGltfAvatarFromMemory(vrmFile(true, 2), "dup.vrm");
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().message.find("both node 2"), std::string::npos) << b.error().message;
  EXPECT_EQ(canonicalForVrmBone("leftThumbMetacarpal", false), "l_thumb1");
  EXPECT_EQ(canonicalForVrmBone("leftThumbProximal", true), "l_thumb1");
  EXPECT_EQ(canonicalForVrmBone("rightLittleDistal", false), "r_pinky3");
  EXPECT_EQ(canonicalForVrmBone("upperChest", false), "upper_chest");
  EXPECT_EQ(canonicalForVrmBone("leftEye", false), "");
}

TEST(GltfVrm, ExplicitMapsAreCheckedAgainstTheSkeleton) {
  auto avatar = importGltfAvatarFromMemory(vrmFile(false), "avatar.vrm");
  ASSERT_TRUE(avatar.ok());
  JointMap map;
  map.name = "mine";
  map.canonical = {"hips", "head"};
  map.joint = {"hips", "no_such_joint"};
  auto bad = explicitJointMap(map, avatar->skeleton);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("no_such_joint"), std::string::npos);
  // A partial map is completed by inference.
  map.joint = {"hips", "head"};
  auto partial = explicitJointMap(map, avatar->skeleton);
  ASSERT_TRUE(partial.ok()) << partial.error().message;
  EXPECT_EQ(partial->map.jointFor("l_upperarm"), "l_upperarm");
}

// Run with --gtest_also_run_disabled_tests and VISTEL_WRITE_SEEDS_DIR set: writes small
// textured and VRM files there (the seeds in tests/fuzz/corpus/gltf were made this way).
TEST(GltfLook, DISABLED_WritesFuzzSeedsWhenAsked) {
  const char* dir = std::getenv("VISTEL_WRITE_SEEDS_DIR");
  if (dir == nullptr) GTEST_SKIP() << "VISTEL_WRITE_SEEDS_DIR is not set";
  const auto tiny =
      test::makePng(2, 2, [](int x, int y) { return glm::u8vec4(200 * x, 200 * y, 90, 255); });
  auto box = encodeGlb(test::texturedBoxScene(tiny));
  ASSERT_TRUE(box.ok());
  EXPECT_TRUE(writeFileBytes(std::string(dir) + "/textured_box.glb", *box).ok());
  EXPECT_TRUE(writeFileBytes(std::string(dir) + "/humanoid_vrm1.vrm", vrmFile(false)).ok());
  EXPECT_TRUE(writeFileBytes(std::string(dir) + "/humanoid_vrm0.vrm", vrmFile(true)).ok());
}

}  // namespace
}  // namespace vistel
