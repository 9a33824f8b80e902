// Independent checks of triangle meshes for the synth tests (written apart from the code
// under test): topology, self-intersections, inside/outside by winding number, OBJ output.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include <glm/glm.hpp>

namespace vistel::test {

struct Topology {
  bool edges_paired = false;     // every directed edge once, its reverse once (closed,
                                 // consistently oriented, each edge in two triangles)
  int nonmanifold_vertices = 0;  // vertices whose triangles form more than one fan
  int degenerate_triangles = 0;  // repeated index or area below 1e-12 m^2
  int components = 0;            // connected components (by shared vertices)
  int unused_vertices = 0;
  long euler = 0;  // V - E + F
};
Topology analyseTopology(std::span<const glm::vec3> positions,
                         std::span<const std::uint32_t> indices);

// Pairs of triangles that share no vertex but intersect.
int countSelfIntersections(std::span<const glm::vec3> positions,
                           std::span<const std::uint32_t> indices);

// Generalised winding number of a closed mesh around p (~1 inside, ~0 outside).
double windingNumber(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                     const glm::vec3& p);

// Writes a Wavefront OBJ (positions and faces) for a quick look; false on I/O failure.
bool writeObj(const std::string& path, std::span<const glm::vec3> positions,
              std::span<const std::uint32_t> indices);

}  // namespace vistel::test
