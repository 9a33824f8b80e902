// A digitized part as synthesis sees it: a triangle mesh read through OpenMesh's readers
// (.obj, .ply, .off, .stl; polygons as fans) with its texture coordinates where the file
// has them, the vertices it repeats at texture seams joined by a weld map, its boundary
// loops (the rims the blend regions are stitched to) and vertex normals.
//
// Space: the file's (model space of the skeleton source, metres). Cost: O(vertices +
// triangles) after reading.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "offline/compare/triangle_soup.hpp"

namespace vistel {

struct PartMesh {
  TriangleSoup mesh;                // as read (vertices repeated at texture seams)
  std::vector<glm::vec2> uvs;       // per vertex, or empty (the file has none)
  std::vector<std::uint32_t> weld;  // per vertex: the first vertex at the same place
  std::vector<glm::vec3> normals;   // per vertex, area-weighted over the welded fan (unit)
};

// A rim of the part: welded vertices (PartMesh::weld representatives) in the direction the
// part's triangles run along it, closed (the last joins the first).
struct BoundaryLoop {
  std::vector<std::uint32_t> vertices;
  glm::vec3 centroid{0.0f};  // mean of the vertices
  float length = 0.0f;       // perimeter, metres
  bool simple = true;        // false when a vertex repeats (two rims touching at a point)
};

// Reads a part file. Errors name the file and why (unreadable, no triangles, non-finite).
Result<PartMesh> readPartMesh(const std::string& path);

// A part from memory (weld map and normals computed); `uvs` per vertex or empty.
PartMesh makePartMesh(TriangleSoup mesh, std::vector<glm::vec2> uvs);

// The part's boundary loops: each directed welded edge with no opposite edge is a rim
// edge; rims are followed edge to edge (at a vertex with several outgoing rim edges the
// one turning least is taken). Loops shorter than 3 vertices are dropped.
std::vector<BoundaryLoop> boundaryLoops(const PartMesh& part);

// Drops the triangles with two edges on the rim (the spikes a cut leaves along it, which
// would fold the region zipped onto them), `rounds` times over; weld map and normals
// recomputed. The vertices stay (unreferenced where all their triangles went). Returns
// the number dropped.
int trimRimSpikes(PartMesh& part, int rounds);

}  // namespace vistel
