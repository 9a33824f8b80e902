// A recorded room (room_recorder.hpp) as glTF 2.0 binary (.glb): one skinned mesh per
// member, one animation. Written without tinygltf (the runtime does not link it); the
// output is meant to pass the Khronos glTF validator with no errors.
//
// Layout (node names are the members' and the props' names):
// - per member, a node named after the member placed at its seat (translation, yaw about
//   +Y), parent of the avatar's joint hierarchy (joint nodes named "<name>:<joint>", as
//   Mixamo prefixes its bones: every node name is unique, which players that bind
//   animation tracks by name, such as three.js before r125, need; rest scale kept); a
//   scene-root node "<name> avatar" draws the avatar's mesh with a skin over those joints
//   (inverse bind matrices from the skeleton). Members sharing an avatar share its mesh
//   and inverse bind matrices.
// - per prop, a node named "ball N" with the ball's icosphere mesh, translated to its centre.
// - one animation "room": LINEAR rotation / translation channels for every joint, root,
//   seat and prop that moved (a channel whose keys all hold one value becomes the node's
//   static transform instead), and a STEP scale channel on a member's or prop's node that is
//   0 outside its spans (before it joined, after it left, while it was away) and 1 inside.
// Key times are seconds from the recording's start, as float32 (keys that float32 cannot
// keep apart are dropped). Rotations are float32 unit quaternions; positions, normals,
// weights float32; joints unsigned byte (<= 256 joints) or short; indices short or int.
//
// Members without an avatar (`avatar` null) or whose avatar's joint count differs from their
// postures' are left out with a warning in the summary; props without a model likewise.
// Fails only when nothing at all can be written or the data is not finite.
#pragma once

#include <cstdint>
#include <vector>

#include "common/base/result.hpp"
#include "common/record/room_recorder.hpp"

namespace vistel::record {

// The .glb bytes; `summary` (optional) receives the counts and warnings (not the size).
// Cost: O(vertices of the distinct avatars + keys); allocates the output.
Result<std::vector<std::uint8_t>> encodeRoomGlb(const RoomRecording& recording,
                                                RecordingSummary* summary = nullptr);

}  // namespace vistel::record
