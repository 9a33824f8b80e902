// The offline (OpenMesh) form of an avatar's skin: a triangle mesh whose vertices carry
// the skin's normals, joints and weights as properties. Offline tools (import, fitting,
// building) work on it; the runtime reads the flat SkinMesh made from it.
#pragma once

#include <array>
#include <cstdint>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "common/anim/skin_mesh.hpp"

namespace vistel {

struct SkinTriMeshTraits : public OpenMesh::DefaultTraits {
  VertexAttributes(OpenMesh::Attributes::Normal);
};
using SkinTriMesh = OpenMesh::TriMesh_ArrayKernelT<SkinTriMeshTraits>;

using SkinJointSlots = std::array<std::uint16_t, kMaxInfluences>;  // joint per slot
using SkinWeightSlots = std::array<float, kMaxInfluences>;         // weight per slot (0 unused)

// Names of the vertex properties (OpenMesh::VPropHandleT<SkinJointSlots> and
// <SkinWeightSlots>) that buildSkinTriMesh adds; find them with get_property_handle.
inline constexpr const char* kSkinJointsProperty = "vistel:joints";
inline constexpr const char* kSkinWeightsProperty = "vistel:weights";

// What OpenMesh found in the triangle list.
struct SkinTopology {
  int boundary_edges = 0;         // edges with a face on one side only (holes, seams)
  int non_manifold_vertices = 0;  // vertices whose faces do not form a single fan
  int rejected_triangles = 0;     // triangles OpenMesh refused (complex edge or vertex:
                                  // a third face on an edge, inconsistent winding)
  int degenerate_triangles = 0;   // triangles that repeat a vertex (not added)
  int isolated_vertices = 0;      // vertices no triangle uses
};

// Builds the OpenMesh form of `skin`: vertex i is skin vertex i (position, normal, joint
// and weight slots, the unused ones zero), one face per triangle that OpenMesh accepts
// (in order; the others are counted, not added). `out` must be empty. Cost: O(n + t).
SkinTopology buildSkinTriMesh(const SkinMesh& skin, SkinTriMesh& out);

// Copies the per-vertex data of `mesh` (positions, normals, joint and weight slots) back
// into `skin`, whose vertex count and influence count must match the mesh it was built
// from; the triangle list of `skin` is kept as it is (it also holds the triangles
// OpenMesh refused).
void flattenSkinTriMesh(const SkinTriMesh& mesh, SkinMesh& skin);

}  // namespace vistel
