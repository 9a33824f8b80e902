// libFuzzer target: the glTF avatar importer on arbitrary bytes (GLB or JSON). Nothing may
// crash, hang or read out of bounds; whatever it accepts must be a valid avatar.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "offline/gltf/gltf_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vistel;
  Result<AvatarModel> avatar = importGltfAvatarFromMemory(std::span<const std::uint8_t>(data, size),
                                                          "fuzz.glb", "/nonexistent");
  if (avatar.ok() && !validateAvatar(*avatar).ok()) std::abort();
  if (!avatar.ok() && avatar.error().message.empty()) std::abort();
  return 0;
}
