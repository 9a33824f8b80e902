// Contact force per body part of one deformed body (issue 25 item 10: force out), from
// Step 3's per-vertex results (common/deform DeformState: pressure, contact partner, deformed
// positions and normals). The body parts are the avatar's implicit primitives (head, torso,
// l_hand, ..., as its primitive map names them) grouped by primitivePart, so that the fingers
// and toes the builder adopted count with their hand and foot; a vertex belongs to the part
// of its owning primitive (calibration.prims[v][0]: the limb of a limb vertex, the joint
// sphere of a joint vertex, the carrying primitive of a free one).
//
// Per contact vertex v (touching another body; self-contact is internal and left out):
//   f_v = -p_v * A_v * n_v,  A_v = one third of the areas of v's incident faces
// (deformed positions), summed per part. p_v: pressure (Pa), n_v: outward unit normal, so a
// part pressed by a ball is pushed away from the ball, into the body. The sum over parts is
// a vertex-based quadrature of the face-based BodyContact force of Step 3 (close to it, not
// equal: that one counts only faces whose three vertices touch).
//
// Space: forces are returned in the body's model space (the avatar's +X left, +Y up,
// +Z forward), given the rotation taking world to model; newtons, square metres.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel {

// The static part of one avatar, built once (allocates; O(nvert + ntri)).
struct PartForceLayout {
  std::vector<std::string> names;         // (npart) the parts' names, in model order
  std::vector<std::int16_t> vertex_part;  // (nvert) owning part, -1 none
  std::vector<std::uint32_t> vf_offsets;  // (nvert + 1) into vf_faces
  std::vector<std::uint32_t> vf_faces;    // incident faces per vertex
  std::vector<std::uint32_t> indices;     // the skin's triangles (3 * ntri)

  int partCount() const { return static_cast<int>(names.size()); }
  int vertexCount() const { return static_cast<int>(vertex_part.size()); }
};

// Fails when the avatar has no implicit model or its calibration does not fit its skin.
Result<PartForceLayout> makePartForceLayout(const AvatarModel& avatar);

// The part of this name, or -1.
int findPart(const PartForceLayout& layout, std::string_view name);

struct PartForce {
  glm::vec3 force{0.0f};  // N, model space: the contact force on this part
  float area = 0.0f;      // m^2 of its contact (one third of each contact vertex's faces)
  int vertices = 0;       // contact vertices
};

// One body's Step 3 results this frame (world space), as DeformState holds them.
struct PartForceInput {
  std::span<const glm::vec3> positions;        // deformed positions (nvert), world
  std::span<const glm::vec3> normals;          // deformed unit normals (nvert), world
  std::span<const float> pressure;             // Pa (nvert)
  std::span<const std::int16_t> contact_body;  // partner body per vertex, -1 none (nvert)
  int self_body = -1;                          // this body's index: its self-contact is left out
  glm::mat3 world_to_model{1.0f};              // rotation taking world vectors to model space
};

// Writes out[part] for every part (out: npart entries; all zero when the input's sizes do
// not match the layout). Allocates nothing; O(nvert) plus O(valence) per contact vertex.
void computePartForces(const PartForceLayout& layout, const PartForceInput& input,
                       std::span<PartForce> out);

}  // namespace vistel
