// Simplifying a synthesized skin where it is flat (issue 24: "the result simplified where
// flat", with OpenMesh's decimater). The lofted blend regions carry a ring every rim edge
// length whatever their curvature; halfedge collapses take out the vertices the surface
// does not need.
//
// The mesh handed to OpenMesh is the skin with the vertices it repeats at texture seams
// joined (exactly equal positions are one vertex), so that it is one half-edge mesh. Then
// OpenMesh's DecimaterT collapses halfedges in the order of ModQuadricT's error (Garland
// and Heckbert 1997, area-weighted), each collapse allowed only when
//   - ModHausdorffT: every point the collapse takes out (the removed vertices accumulated
//     on the faces) stays within `max_error_m` of the new faces around it,
//   - and the other way (a module of ours): the new faces around it lie within
//     `max_error_m` of the input's surface at 12 points of a barycentric grid on each,
//   - ModNormalFlippingT: no face around it turns by more than `max_normal_turn_deg`,
//   - ModAspectRatioT: no face around it gets longer than `max_aspect_ratio` times its
//     height, unless the worst one there already was,
//   - the removed vertex may be removed (`removable`), is no seam vertex (repeated), lies
//     on no boundary, and OpenMesh's link condition holds (no fold, no non-manifold edge).
// A halfedge collapse moves no surviving vertex and makes none, so every per-vertex
// attribute of the survivors (weights, texture coordinates) stays valid as it is: the
// result maps back onto the input's vertices and triangles (DecimatedMesh).
//
// Triangles OpenMesh cannot take (they would make a non-manifold edge or vertex) are kept
// as they are, their vertices and those vertices' neighbours held.
//
// Measured on the default avatar's 3 cm round trip, regions only: the result within
// 0.50 mm of the undecimated skin, the undecimated skin within 0.68 mm of the result (the
// bound is checked at the removed vertices, not between them).
//
// Space: the input's (metres). Bad input: indices out of range, flags of the wrong size,
// a bound not > 0 are refused (an Error). Cost: O(n log n) in the triangles, each collapse
// tried with 12 nearest-point queries per face around it: about 0.1 s for the regions of
// a 10,000-vertex skin, 3 s for the whole of it (Release).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct DecimationOptions {
  float max_error_m = 0.0005f;        // removed vertices to the result's surface, metres (> 0)
  float max_normal_turn_deg = 30.0f;  // per collapse, for each face around it
  float max_aspect_ratio = 10.0f;     // longest edge over its height
};

struct DecimatedMesh {
  std::vector<std::uint32_t> kept;     // per result vertex: the input vertex (increasing)
  std::vector<std::uint32_t> indices;  // result triangles (3 each), result numbering
  std::vector<std::uint32_t> origin;   // per result triangle: the input triangle it was
                                       // (increasing: the input's order is kept)
  int collapses = 0;
  int unmanaged_triangles = 0;  // that OpenMesh could not take, kept as they are
};

// Decimates the triangle mesh (`positions` per vertex, `indices` 3 per triangle, the
// input's orientation kept). `removable`: per vertex, nonzero where the vertex may be
// collapsed away (others stay); empty: every vertex may. Triangles whose corners change
// take, for a corner at a vertex the input repeats, the first of its copies.
Result<DecimatedMesh> decimateMesh(std::span<const glm::vec3> positions,
                                   std::span<const std::uint32_t> indices,
                                   std::span<const std::uint8_t> removable,
                                   const DecimationOptions& options);

}  // namespace vistel
