// An avatar as a skinned glTF 2.0 binary (.glb) for the browser (three.js GLTFLoader):
// its prototype skin bound to its skeleton in the rest posture, one material. The
// server may not link offline/gltf (the runtime never does), so this is a small writer of
// its own.
//
// Layout: node 0 is the mesh node (a scene root, identity); nodes 1..njoint are the
// joints in skeleton order with their rest_local TRS (joint j is node j + 1; the skin's
// joints array lists them in that order, so a viewer's skeleton.bones[j] is joint j).
// Attributes: POSITION, NORMAL (unit; recomputed when the file has none), JOINTS_0 /
// WEIGHTS_0 (four influences: a vertex with more keeps its four largest, renormalised);
// indices u32. Model space: metres, +Y up, the avatar faces +Z.
//
// Errors: an avatar that fails validateAvatar, or one with no triangles. Cost: O(nvert +
// njoint); allocates the output (~64 bytes per vertex).
#pragma once

#include <cstdint>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel::server {

Result<std::vector<std::uint8_t>> avatarGlb(const AvatarModel& avatar);

}  // namespace vistel::server
