// Vertices a mesh repeats at one position: glTF and OBJ meshes split a vertex wherever its
// texture coordinates or normals change (seams), so one point of the surface is several
// vertices. firstCopies names, per vertex, the first vertex at exactly its position, which
// joins the copies back into one surface (components, boundaries, half-edge meshes).
// Positions compare exactly (0 and -0 are one); no tolerance. Cost: O(nvert) expected.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vistel {

// Per vertex: the smallest index whose position equals its own (itself when none is earlier).
std::vector<std::uint32_t> firstCopies(std::span<const glm::vec3> positions);

}  // namespace vistel
