// libFuzzer target: importGltfAvatarFromMemory (offline/gltf/gltf_import.hpp) on arbitrary
// bytes, as a .glb or .gltf file (external buffers are looked up in a folder that does not
// exist). Properties: nothing crashes, hangs or reads out of bounds; a rejection names
// the source; an accepted avatar validates, its report counts are sane, and it survives
// the .vavatar round trip (encodeAvatar -> decodeAvatar), as `vistel-avatar import` needs.
//
// Seeds: small avatars exported by encodeGlb (skinned, with a morph animation, unskinned)
// and the same skinned file as .gltf JSON with its buffer in a data: URI; gltf.dict lists
// glTF's keys and constants.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/avatar/avatar_io.hpp"
#include "common/glb/glb_container.hpp"
#include "common/glb/gltf_export.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/fuzz/fuzz_support.hpp"
#include "tests/fuzz/tiny_avatar.hpp"

namespace {

using namespace vistel;
using fuzz::check;

// ---- seeds -------------------------------------------------------------------------------

std::string base64(std::span<const std::uint8_t> bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? bytes[i + k] : 0u);
    for (std::size_t k = 0; k < 4; ++k) {
      out.push_back(k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=');
    }
  }
  return out;
}

std::vector<std::uint8_t> glbOf(const GltfScene& scene) {
  Result<std::vector<std::uint8_t>> glb = encodeGlb(scene);
  check(glb.ok(), "the seed scene encodes");
  return std::move(*glb);
}

// The .gltf (JSON) form of a .glb: its JSON with the BIN chunk as a data: URI.
std::vector<std::uint8_t> gltfJsonOf(std::span<const std::uint8_t> glb) {
  Result<GlbChunks> chunks = parseGlbContainer(glb, "seed.glb");
  check(chunks.ok(), "the seed's container parses");
  nlohmann::json json = nlohmann::json::parse(chunks->json.begin(), chunks->json.end());
  json["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(chunks->bin);
  const std::string text = json.dump(1);
  return {text.begin(), text.end()};
}

std::vector<fuzz::Seed> makeSeeds() {
  const AvatarModel avatar = fuzz::tinyAvatar(3, 2);
  const std::vector<std::uint8_t> skinned = glbOf(restAvatarScene(avatar));

  GltfScene animated = restAvatarScene(fuzz::tinyAvatar(2, 1));
  GltfFrame frame;
  for (const glm::vec3& p : animated.mesh.positions) frame.positions.push_back(p * 1.1f);
  animated.frames = {frame, frame};

  GltfScene unskinned = restAvatarScene(avatar);
  unskinned.skin.reset();

  const std::vector<std::uint8_t> json = gltfJsonOf(skinned);
  check(importGltfAvatarFromMemory(skinned, "seed.glb").ok(), "the skinned seed imports");
  check(importGltfAvatarFromMemory(json, "seed.gltf").ok(), "the JSON seed imports");
  return {{"skinned.glb", skinned},
          {"animated.glb", glbOf(animated)},
          {"unskinned.glb", glbOf(unskinned)},
          {"skinned.gltf", json}};
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  GltfImportReport report;
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(
      std::span<const std::uint8_t>(data, size), "fuzz.glb", "/nonexistent/fuzz", {}, &report);
  if (!avatar.ok()) {
    check(avatar.error().message.find("fuzz.glb") != std::string::npos,
          "a rejection names the source");
    return 0;
  }
  check(validateAvatar(*avatar).ok(), "an imported avatar validates");
  check(report.skin >= 0 && report.primitives >= 1, "the report names the skin used");
  check(report.boundary_edges >= 0 && report.non_manifold_vertices >= 0 &&
            report.rejected_triangles >= 0 && report.unweighted_vertices >= 0,
        "report counts are non-negative");

  // What `vistel-avatar import` does next: save and load the avatar.
  Result<AvatarModel> loaded = decodeAvatar(encodeAvatar(*avatar), "fuzz.vavatar");
  if (!loaded.ok()) std::fprintf(stderr, "%s\n", loaded.error().message.c_str());
  check(loaded.ok(), "an imported avatar survives the .vavatar round trip");
  return 0;
}
