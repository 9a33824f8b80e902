// TriangleSoup: positions and triangles, nothing else (a skin without its skeleton, a part
// mesh read from OBJ/PLY/OFF/STL). weldVertices joins vertices at the same place, so that
// a mesh split at texture seams is judged as the surface it is.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct TriangleSoup {
  std::vector<glm::vec3> positions;    // metres
  std::vector<std::uint32_t> indices;  // 3 per triangle, counter-clockwise outward
};

// Checks sizes, indices in range and finite positions; the message names the first fault.
Status validateSoup(const TriangleSoup& soup);

// Vertices closer than `tolerance` (m) to an earlier one are merged into it (a grid of
// tolerance-sized cells; first come keeps its place), triangles re-indexed; triangles that
// collapse (two corners merged) are dropped. Cost: O(vertices + triangles).
TriangleSoup weldVertices(const TriangleSoup& soup, float tolerance);

// Reads a triangle mesh with OpenMesh's readers (.obj, .ply, .off, .stl); polygons are
// triangulated as fans. With `uvs`, also the per-vertex texture coordinates (left empty
// when the file has none; a non-finite one is an error). Errors name the file and why.
Result<TriangleSoup> readMeshFile(const std::string& path, std::vector<glm::vec2>* uvs = nullptr);

}  // namespace vistel
