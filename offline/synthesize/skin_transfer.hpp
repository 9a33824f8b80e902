// Skin weights for points near a skinned surface (the skeleton source's skin): the
// weights at the nearest surface point, blended from its triangle's corners by
// barycentric coordinates. Gives a part's vertices the weights the source skin has where
// they lie, and blends two sets of influences across a region.
//
// Ownership: keeps a reference to the skin. Space: the skin's (model space, metres).
// Cost: one BVH nearest-point query per point.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/skin_mesh.hpp"
#include "offline/compare/triangle_tree.hpp"

namespace vistel {

// (joint, weight) pairs, each joint once, weights >= 0.
using Influences = std::vector<std::pair<std::uint16_t, float>>;

class SkinTransfer {
 public:
  // `skin` valid (validateSkinMesh) with triangles.
  explicit SkinTransfer(const SkinMesh& skin);

  Influences at(const glm::vec3& p) const;

 private:
  const SkinMesh& skin_;
  TriangleSoup soup_;
  TriangleTree tree_;
};

// (1 - t) a + t b, joint by joint.
Influences blendInfluences(const Influences& a, const Influences& b, float t);

// The k largest influences, normalised, into k slots (unused slots joint 0, weight 0).
// An empty set gets `fallback_joint` with weight 1.
void storeInfluences(const Influences& in, std::uint16_t fallback_joint,
                     std::span<std::uint16_t> joints, std::span<float> weights);

}  // namespace vistel
