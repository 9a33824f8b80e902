// Polygonizes an implicit body: marching tetrahedra over a conforming tetrahedralisation
// of an adaptively refined octree. Because the tetrahedra form one simplicial complex and
// no sample is exactly zero, the output is a closed, consistently oriented 2-manifold
// (every edge in exactly two triangles, outward counter-clockwise) that does not
// self-intersect.
//
// Refinement: cubes of edge `coarse_cell` everywhere, halved as often as each fine region
// asks inside it and graded 2:1 around it (each coarser ring one coarse cube wide).
// Cubes next to finer ones are split into tetrahedra by coning their (subdivided) faces to
// their centre; all others use the six-tetrahedron Kuhn split, whose face diagonals agree
// between neighbours. Cubes the field proves empty (|value(centre)| > half diagonal, the
// field being 1-Lipschitz) are skipped, so the cost follows the surface area.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "offline/synth/body_plan.hpp"
#include "offline/synth/implicit_body.hpp"

namespace vistel::synth {

struct PolygonizeSettings {
  Box domain;                            // must contain the whole surface (model space)
  float coarse_cell = 0.008f;            // metres
  std::vector<FineRegion> fine_regions;  // halvings 1..3 each
  float shape_scale = 1.0f;              // the body plan's scale (sizes of its primitives)
};

struct TriangleMesh {
  std::vector<glm::vec3> positions;    // model space (nvert)
  std::vector<std::uint32_t> indices;  // counter-clockwise seen from outside (3 * ntri)
};

// The zero set of `body` inside settings.domain. Only the largest connected component is
// kept (the body is one piece; this drops stray specks, if any). Deterministic.
TriangleMesh polygonize(const ImplicitBody& body, const PolygonizeSettings& settings);

}  // namespace vistel::synth
