// Cutting a whole avatar into limb parts (vistel-avatar cut; issue 24's inverse of
// synthesis, for tests and for users who start from a whole scan).
//
// Segments: head (head, neck), torso (hips, spine, chests, clavicles), and per side the
// upper arm, forearm, hand (with the fingers), thigh, shin and foot (with the toes). A
// skeleton joint the joint map does not name belongs to the segment of its nearest named
// ancestor; a vertex belongs to the segment carrying most of its skin weight, a triangle to
// the segment of most of its corners.
//
// Cuts: where two adjacent segments meet (neck, shoulders, elbows, wrists, hips, knees,
// ankles), the seam is the set of vertices with a neighbour across it; every triangle with
// a corner of either segment within band / 2 of that seam (Euclidean) is removed, leaving
// a band about `band` wide between the two parts. What remains of each segment is one part.
//
// Space: the avatar's model space, rest posture (metres). Cost: O(seam vertices x
// vertices) per joint, well under a second for a 13k-vertex avatar.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/compare/triangle_soup.hpp"

namespace vistel {

struct CutPart {
  std::string segment;                      // "head", "torso", "l_upperarm", ...
  std::string bone;                         // the avatar's joint the segment starts at
  TriangleSoup mesh;                        // its vertices re-indexed from 0
  std::vector<glm::vec2> uvs;               // per part vertex, or empty (no texture coords)
  std::vector<std::uint32_t> source_index;  // the avatar's vertex of each part vertex
};

struct CutJoint {
  std::string canonical;  // the canonical joint where the child segment starts ("l_forearm")
  std::string joint;      // the avatar's name for it
  std::string parent_segment, child_segment;
  glm::vec3 position{0.0f};  // rest position, model space
  int seam_vertices = 0;     // vertices on the seam before the band was removed
  int removed_triangles = 0;
};

struct AvatarCut {
  std::vector<CutPart> parts;    // segments with triangles left, in segment order
  std::vector<CutJoint> joints;  // joints whose segments meet on the skin
  int removed_triangles = 0;
};

// Fails when the map names neither hips nor head in the skeleton, band is not in
// (0, 0.5] m, or the avatar is invalid.
Result<AvatarCut> cutAvatar(const AvatarModel& avatar, const JointMap& map, float band_m);

// The PARTS.toml text for a cut whose parts were written as `<segment>.<extension>` next to
// it: the source, the band, a [[part]] per part (file, segment, bone, counts) and a
// [[joint]] per cut joint (its segments and the blend radius, band / 2).
std::string partsToml(const AvatarCut& cut, const std::string& source, float band_m,
                      const std::string& extension);

}  // namespace vistel
