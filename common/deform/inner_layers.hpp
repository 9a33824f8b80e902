// Inner layers of a skin mesh (issue 25): the parts of a mesh that lie inside its outer
// skin — eyeballs, teeth, a tongue, an inner mouth bag — are carried rigidly with their
// bones by the skinning and never deformed: the deformable component neither projects them
// onto a field nor lets them touch anything.
//
// Detection (findInnerLayers, at model build time, not per frame): the mesh's connected
// components, where triangles join vertices and vertices at the same position are one (glTF
// meshes split their vertices along UV and normal seams); a component is an inner layer when
// at least InnerLayerOptions::min_inside_fraction of its vertices lie inside another
// component (a larger one, whose box holds the component's centre). The largest component
// (by vertex count), the outer skin, is never one. Inside: ray parity along the six axis
// directions against that component's triangles alone, inside when at least four of the six
// rays cross it an odd number of times (a skin with holes at the eye sockets or the mouth
// still holds what is behind them); components nested in inner ones (a cornea in an eyeball)
// are inner too.
//
// Carrying (carryInnerLayersRigidly): an inner vertex becomes a free vertex with no
// primitive, no pair, and Calibration::rigid = kRigidInner, which the model's codec keeps.
// Such a vertex has no collider, so Step 2 leaves it at its skinned position (bit for bit),
// it is never relaxed, smoothed or in contact, its faces never count in contact areas or
// forces, and no primitive's skin weights are fitted to it (calibrate.hpp).
//
// Space: any one space for all positions (bind-pose model space in the builder), metres.
// Cost: O(n log n) for the components (n vertices) plus, per component other than the
// largest, O(its vertices x the triangles of a container's grid cell) with a 2-D grid over
// each container's triangles per axis (built only for the containers a component is tested
// against); milliseconds for a 15k-vertex mesh with a few inner parts.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/deform/shape.hpp"

namespace vistel {

struct InnerLayerOptions {
  float min_inside_fraction = 0.9f;  // share of a component's vertices that must lie inside
                                     // another component, in (0, 1]
};

// One connected component of the mesh.
struct MeshComponent {
  int vertices = 0;           // vertices in it (those in no triangle form no component)
  int triangles = 0;          // triangles in it
  Bounds box;                 // of its vertices
  bool inner = false;         // an inner layer
  int container = -1;         // inner: the component it lies inside
  float inside_share = 0.0f;  // inner: the share of its vertices inside the container
};

struct InnerLayers {
  std::vector<MeshComponent> components;  // largest first (by vertices), then by first vertex
  std::vector<std::int32_t> component;    // (nvert) each vertex's component; -1: in no triangle
  std::vector<std::uint8_t> inner;        // (nvert) 1: the vertex is on an inner layer
  int outer = -1;                         // the largest component (-1: no triangle at all)
  int inner_vertices = 0;                 // vertices flagged in `inner`

  int innerLayerCount() const {
    int n = 0;
    for (const MeshComponent& c : components) n += c.inner ? 1 : 0;
    return n;
  }
};

// Finds the inner layers of a triangle mesh (positions: nvert, indices: 3 * ntri). Bad
// input (an index count not a multiple of 3, an index out of range, a non-finite position or
// option) gives an Error naming it.
Result<InnerLayers> findInnerLayers(std::span<const glm::vec3> positions,
                                    std::span<const std::uint32_t> indices,
                                    const InnerLayerOptions& options = {});

// Makes the vertices flagged in `inner` (nvert) carried rigidly (see the header): free, no
// primitives, rigid = kRigidInner, w = 1 and a positive slope where those arrays are sized,
// and their pairs dropped where the pair arrays are. vertex_class and prims must have nvert
// entries (else an Error; nothing changes); rigid is sized (zeros) if it is not. Returns how
// many vertices it marked.
Result<int> carryInnerLayersRigidly(std::span<const std::uint8_t> inner, Calibration& calibration);

// Whether vertex v of a calibrated model is on an inner layer.
inline bool innerVertex(const Calibration& c, std::size_t v) {
  return v < c.rigid.size() && c.rigid[v] == kRigidInner;
}

}  // namespace vistel
