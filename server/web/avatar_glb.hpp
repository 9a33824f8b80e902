// An avatar as a skinned glTF 2.0 binary (.glb) for the browser (three.js GLTFLoader):
// its prototype skin bound to its skeleton in the rest posture, with its look (texture
// coordinates, materials, textures), written by common/glb's exporter.
//
// Layout (common/glb/gltf_export.hpp): node 0 is the mesh node (a scene root); nodes
// 1..njoint are the joints in skeleton order (joint j is node j + 1; the skin's joints
// array lists them in that order, so a viewer's skeleton.bones[j] is joint j). Attributes:
// POSITION, NORMAL (recomputed when the avatar has none), TEXCOORD_0 with a look,
// JOINTS_0 / WEIGHTS_0 (four influences: a vertex with more keeps its four largest,
// renormalised); one primitive per submesh. Model space: metres, +Y up, faces +Z.
//
// Errors: an avatar that fails validateAvatar, or one with no triangles. Cost: O(nvert +
// njoint + texture bytes); allocates the output.
#pragma once

#include <cstdint>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel::server {

Result<std::vector<std::uint8_t>> avatarGlb(const AvatarModel& avatar);

}  // namespace vistel::server
