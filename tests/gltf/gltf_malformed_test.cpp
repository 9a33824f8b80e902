// Malformed glTF input: every failure is an Error naming the file and the element; nothing
// crashes (these tests also run under ASan+UBSan).
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "common/glb/glb_container.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/gltf/gltf_test_models.hpp"

namespace vistel {
namespace {

// Imports and expects an error whose message contains every fragment.
void expectError(const std::vector<std::uint8_t>& bytes,
                 std::initializer_list<std::string_view> fragments) {
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(bytes, "bad.glb");
  ASSERT_FALSE(avatar.ok()) << "accepted a malformed file";
  const std::string& message = avatar.error().message;
  EXPECT_EQ(message.rfind("bad.glb", 0), 0u) << message;
  for (std::string_view f : fragments) EXPECT_NE(message.find(f), std::string::npos) << message;
}

void expectFileError(const test::GltfBuilder& file,
                     std::initializer_list<std::string_view> fragments) {
  expectError(file.glb(), fragments);
}

test::ChainGltf smallChain() {
  test::ChainOptions opt;
  opt.joints = 4;
  opt.helper_node = false;
  opt.normals = true;
  return test::makeChainGltf(opt);
}

void putU32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t v) {
  std::memcpy(bytes.data() + at, &v, 4);
}

TEST(GltfMalformed, EveryTruncationFailsCleanly) {
  const std::vector<std::uint8_t> full = smallChain().file.glb();
  ASSERT_TRUE(importGltfAvatarFromMemory(full, "bad.glb").ok());
  for (std::size_t n = 0; n < full.size(); ++n) {
    const std::vector<std::uint8_t> cut(full.begin(),
                                        full.begin() + static_cast<std::ptrdiff_t>(n));
    Result<AvatarModel> avatar = importGltfAvatarFromMemory(cut, "bad.glb");
    ASSERT_FALSE(avatar.ok()) << "accepted the first " << n << " bytes";
    ASSERT_EQ(avatar.error().message.rfind("bad.glb", 0), 0u) << avatar.error().message;
  }
}

TEST(GltfMalformed, TruncatedWithPatchedLengthsFailsCleanly) {
  // Truncations whose header and chunk lengths are patched to agree get past the
  // container check, so the accessors' bounds are what must catch them.
  const std::vector<std::uint8_t> full = smallChain().file.glb();
  std::uint32_t json_length;
  std::memcpy(&json_length, full.data() + 12, 4);
  const std::size_t bin_start = 20 + json_length + 8;
  for (std::size_t n = bin_start; n + 4 <= full.size(); n += 4) {
    std::vector<std::uint8_t> cut(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
    putU32(cut, 8, static_cast<std::uint32_t>(n));
    putU32(cut, bin_start - 8, static_cast<std::uint32_t>(n - bin_start));
    Result<AvatarModel> avatar = importGltfAvatarFromMemory(cut, "bad.glb");
    ASSERT_FALSE(avatar.ok()) << "accepted " << n << " bytes";
  }
}

TEST(GltfMalformed, ContainerErrors) {
  const std::vector<std::uint8_t> good = smallChain().file.glb();
  expectError({}, {"not a glTF file"});
  expectError({'g', 'l', 'T', 'F', 2, 0, 0, 0}, {"shorter than the 12-byte GLB header"});

  std::vector<std::uint8_t> bytes = good;
  bytes[0] = 'X';
  expectError(bytes, {"not a glTF file"});

  bytes = good;
  putU32(bytes, 4, 1);
  expectError(bytes, {"byte 4", "version 1"});

  bytes = good;
  putU32(bytes, 8, static_cast<std::uint32_t>(good.size() + 100));
  expectError(bytes, {"byte 8", "header says"});

  bytes = good;
  putU32(bytes, 12, 0x7fffffff);
  expectError(bytes, {"byte 12", "chunk length"});

  bytes = good;
  putU32(bytes, 16, kGlbChunkBin);
  expectError(bytes, {"first chunk is not JSON"});

  std::uint32_t json_length;
  std::memcpy(&json_length, good.data() + 12, 4);
  bytes = good;
  putU32(bytes, 20 + json_length, 0x7ffffff0);
  expectError(bytes, {"chunk length"});
}

TEST(GltfMalformed, GarbageJson) {
  expectError(assembleGlb("{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [", {}), {});
  expectError(assembleGlb("this is not json at all", {}), {});
  expectError(assembleGlb("[1, 2, 3]", {}), {});
  expectError(assembleGlb("{\"asset\": {\"version\": \"1.0\"}}", {}), {});
  expectError(assembleGlb("{\"asset\": {\"version\": \"2.0\"}}", {}), {"no skinned mesh"});
  const std::string text = "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": \"zero\"}]}";
  expectError(std::vector<std::uint8_t>(text.begin(), text.end()), {});
  expectError(std::vector<std::uint8_t>{0xEF, 0xBB, 0xBF, 'x'}, {"not a glTF file"});
}

TEST(GltfMalformed, AccessorBeyondItsBufferView) {
  test::ChainGltf chain = smallChain();
  const int pos = chain.file.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
  chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["count"] = 100000;
  expectFileError(chain.file,
                  {fmt::format("bad.glb: accessor {}: count 100000 exceeds buffer view", pos)});

  chain = smallChain();
  chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["byteOffset"] = 8;
  expectFileError(chain.file, {fmt::format("accessor {}", pos), "exceeds buffer view"});

  chain = smallChain();
  const std::size_t view = chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["bufferView"];
  chain.file.doc["bufferViews"][view]["byteLength"] = 1u << 30;
  expectFileError(chain.file, {});

  chain = smallChain();
  chain.file.doc["bufferViews"][view]["byteStride"] = 6;
  expectFileError(chain.file, {"tride", "6"});

  chain = smallChain();
  chain.file.doc["bufferViews"][view]["byteStride"] = 4;
  expectFileError(chain.file, {"smaller than the element size"});

  chain = smallChain();
  chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["count"] = 0;
  expectFileError(chain.file, {});

  chain = smallChain();
  chain.file.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 999;
  expectFileError(chain.file, {"accessor 999 does not exist"});
}

TEST(GltfMalformed, WrongAccessorTypes) {
  test::ChainGltf chain = smallChain();
  const int joints = chain.file.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"];
  chain.file.doc["accessors"][static_cast<std::size_t>(joints)]["componentType"] = 5126;
  expectFileError(chain.file, {fmt::format("accessor {}", joints), "float is not allowed"});

  chain = smallChain();
  const int pos = chain.file.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
  chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["type"] = "VEC2";
  expectFileError(chain.file, {"element type VEC2 where VEC3 is required"});

  chain = smallChain();
  chain.file.doc["accessors"][static_cast<std::size_t>(pos)]["componentType"] = 5124;
  expectFileError(chain.file, {});
}

TEST(GltfMalformed, IndexAndJointOutOfRange) {
  // A triangle index beyond the vertices.
  test::ChainGltf chain = smallChain();
  const int idx = chain.file.doc["meshes"][0]["primitives"][0]["indices"];
  const std::size_t view = chain.file.doc["accessors"][static_cast<std::size_t>(idx)]["bufferView"];
  const std::size_t offset = chain.file.doc["bufferViews"][view]["byteOffset"];
  const std::uint16_t big = 60000;
  std::memcpy(chain.file.bin.data() + offset + 2 * 7, &big, 2);
  expectFileError(chain.file, {fmt::format("accessor {}: index 60000 at position 7", idx)});

  // A joint index beyond the skin's joints, with weight.
  chain = smallChain();
  const int joints = chain.file.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"];
  const std::size_t jview =
      chain.file.doc["accessors"][static_cast<std::size_t>(joints)]["bufferView"];
  const std::size_t joffset = chain.file.doc["bufferViews"][jview]["byteOffset"];
  chain.file.bin[joffset + 4 * 3] = 200;  // vertex 3, slot 0 (the strongest weight)
  expectFileError(chain.file,
                  {fmt::format("accessor {} (JOINTS_0): vertex 3 uses joint index 200", joints),
                   "has 4 joints"});

  // A skin joint that is not a node.
  chain = smallChain();
  chain.file.doc["skins"][0]["joints"][1] = 77;
  expectFileError(chain.file, {"skin 0: joint 1 refers to node 77"});

  // Too few inverse bind matrices.
  chain = smallChain();
  const int ibm = chain.file.doc["skins"][0]["inverseBindMatrices"];
  chain.file.doc["accessors"][static_cast<std::size_t>(ibm)]["count"] = 2;
  expectFileError(chain.file, {"skin 0: 2 inverse bind matrices for 4 joints"});

  // A singular inverse bind matrix.
  chain = smallChain();
  const std::size_t iview =
      chain.file.doc["accessors"][static_cast<std::size_t>(ibm)]["bufferView"];
  const std::size_t ioffset = chain.file.doc["bufferViews"][iview]["byteOffset"];
  std::memset(chain.file.bin.data() + ioffset, 0, 48);
  expectFileError(chain.file, {"singular"});
}

TEST(GltfMalformed, NodeGraphErrors) {
  // A cycle: the last joint lists the conversion root as its child.
  test::ChainGltf chain = smallChain();
  chain.file.doc["nodes"][static_cast<std::size_t>(chain.joint_nodes.back())]["children"] = {1};
  expectFileError(chain.file, {});  // two parents or a cycle, whichever is found first

  chain = smallChain();
  chain.file.doc["nodes"][0]["children"] = nlohmann::json::array();  // orphan the chain...
  chain.file.doc["nodes"][static_cast<std::size_t>(chain.joint_nodes.back())]["children"] = {
      chain.joint_nodes[0]};
  expectFileError(chain.file, {"cycle"});

  chain = smallChain();
  chain.file.doc["nodes"][1]["children"].push_back(1);
  expectFileError(chain.file, {"node 1: lists itself as a child"});

  chain = smallChain();
  chain.file.doc["nodes"][1]["children"].push_back(500);
  expectFileError(chain.file, {"node 1: child 500 does not exist"});

  chain = smallChain();
  chain.file.doc["nodes"][1]["rotation"] = {0.0, 0.0, 1.0};
  expectFileError(chain.file, {});

  chain = smallChain();
  chain.file.doc["nodes"][1]["rotation"] = {0.0, 0.0, 0.0, 0.0};
  expectFileError(chain.file, {"node 1: rotation is a zero quaternion"});

  chain = smallChain();
  chain.file.doc["scenes"][0]["nodes"] = {42};
  expectFileError(chain.file, {"scene 0: node 42 does not exist"});

  chain = smallChain();
  chain.file.doc["nodes"][static_cast<std::size_t>(chain.mesh_node)]["skin"] = 3;
  expectFileError(chain.file, {"skin 3 does not exist"});
}

TEST(GltfMalformed, RandomByteMutationsNeverCrash) {
  const std::vector<std::uint8_t> good = smallChain().file.glb();
  std::mt19937 rng(12345);
  int accepted = 0;
  for (int i = 0; i < 1500; ++i) {
    std::vector<std::uint8_t> bytes = good;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) {
      bytes[rng() % bytes.size()] = static_cast<std::uint8_t>(rng());
    }
    Result<AvatarModel> avatar = importGltfAvatarFromMemory(bytes, "bad.glb");
    if (avatar.ok()) {
      ++accepted;
      EXPECT_TRUE(validateAvatar(*avatar).ok());
    } else {
      EXPECT_FALSE(avatar.error().message.empty());
    }
  }
  EXPECT_LT(accepted, 1500);
}

}  // namespace
}  // namespace vistel
