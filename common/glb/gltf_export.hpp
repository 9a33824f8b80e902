// glTF 2.0 binary (.glb) export of a mesh, optionally skinned, optionally textured
// (materials, PNG/JPEG textures embedded), optionally with a vertex animation (all frames in one
// file), written so that the Khronos glTF validator reports no errors (accessor min/max exact, unit
// normals, normalised weights, aligned views).
//
// Layout: node 0 is the mesh node (a scene root); joints follow as nodes 1..njoint in
// skeleton order, in the posture given. A vertex animation is one morph target per frame
// (POSITION, and NORMAL when given, as deltas from the base mesh) and one animation whose
// STEP-interpolated "weights" channel shows frame f alone from time f * frame_time.
// Morph targets apply before skinning: a vertex animation of final (already deformed)
// positions is best written without a skin, or with the skin in the posture the frames
// are relative to. The weights channel holds frames^2 floats, so at most kMaxGltfFrames
// frames go in one file (about 1 GB of data per 10k vertices at that limit).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/glb/glb_builder.hpp"

namespace vistel {

inline constexpr std::size_t kMaxGltfFrames = 4096;

struct GltfMesh {
  std::string name = "skin";
  std::vector<glm::vec3> positions;    // model space, metres (nvert)
  std::vector<glm::vec3> normals;      // (nvert) or empty for none; normalised on writing
  std::vector<std::uint32_t> indices;  // triangles, counter-clockwise outward (3 * ntri)
};

struct GltfSkin {
  std::vector<std::string> joint_names;  // (njoint)
  std::vector<int> parents;              // (njoint); joint 0 is the root (kNoParent), parents
                                         // precede children
  std::vector<glm::mat4> joint_model;    // (njoint) model-space joint transforms in the
                                         // posture the mesh is in (the bind posture): written
                                         // as the joint nodes' TRS; IBM = inverse (affine,
                                         // no shear)
  int influences = 4;                    // slots per vertex, 1..kMaxInfluences
  std::vector<std::uint16_t> joints;     // joint per slot (nvert * influences)
  std::vector<float> weights;            // weight per slot (nvert * influences), >= 0, each
                                         // vertex's sum > 0; normalised on writing
};

// One frame of a vertex animation: the mesh's vertices at that time.
struct GltfFrame {
  std::vector<glm::vec3> positions;  // (nvert) model space
  std::vector<glm::vec3> normals;    // (nvert), or empty in every frame
};

struct GltfScene {
  GltfMesh mesh;
  std::optional<GltfSkin> skin;
  std::vector<GltfFrame> frames;   // empty: no animation
  double frame_time = 1.0 / 30.0;  // seconds per frame (> 0)
  std::string generator = "vistel";
  // Texture coordinates (nvert or none), materials and textures (embedded in the .glb as
  // buffer views), one glTF primitive per submesh; empty: one primitive, no material.
  // Without texture coordinates, materials are written without their textures.
  AvatarLook look;
};

// The .glb bytes of a scene. Fails (naming the part and the element) on inconsistent
// sizes, indices or joints out of range, non-finite values, a vertex with no weight, or
// a file beyond 4 GiB. Cost: O(nvert * (1 + frames) + njoint); allocates the output.
Result<std::vector<std::uint8_t>> encodeGlb(const GltfScene& scene);

// encodeGlb, then an atomic write to `path`.
Status writeGlb(const std::string& path, const GltfScene& scene);

// The skin part of an avatar with its joints in the given posture (njoint model-space
// transforms, e.g. from poseSkeleton).
GltfSkin gltfSkinFromAvatar(const AvatarModel& avatar, std::span<const glm::mat4> joint_model);

// A rigged avatar whose bind posture is the given one: mesh = the posed vertices
// (positions, normals: nvert each, e.g. from skinMesh), skeleton = joint_model, look = the
// avatar's (texture coordinates, materials, textures). Importing the file gives these
// vertex positions, the avatar's joint names and weights, and its look.
GltfScene posedAvatarScene(const AvatarModel& avatar, std::span<const glm::mat4> joint_model,
                           std::span<const glm::vec3> positions,
                           std::span<const glm::vec3> normals);

// The avatar in its rest posture (its prototype skin and rest skeleton).
GltfScene restAvatarScene(const AvatarModel& avatar);

// The looks of a document being built: materials, and the textures and images they use.
class GltfLooks {
 public:
  // Appends a look, its images' bytes as buffer views of `b`; returns the index of the
  // look's first material (a submesh with material m uses first + m). Without texture
  // coordinates the materials are written without textures (a textured primitive needs
  // TEXCOORD_0).
  int append(const AvatarLook& look, GlbBuilder& b);

  // Puts what was appended into the document: "materials", and "textures", "images" and
  // their one sampler when there are textures. Nothing when nothing was appended.
  void writeTo(nlohmann::json& doc) const;

 private:
  nlohmann::json materials_ = nlohmann::json::array();
  nlohmann::json textures_ = nlohmann::json::array();
  nlohmann::json images_ = nlohmann::json::array();
};

// Keeps each vertex's `k` largest influences (1..4), renormalised, for viewers that read
// JOINTS_0/WEIGHTS_0 alone (three.js). A skin with k or fewer is left as it is.
void keepLargestInfluences(GltfSkin& skin, int k);

}  // namespace vistel
