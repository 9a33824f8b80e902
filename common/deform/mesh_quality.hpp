// Measures of a deformed skin (DESIGN.md §3 "The hard case": judge by numbers, not by
// eye): inverted faces, triangle self-intersections, and how deep one set of vertices
// lies behind a set of faces. Also the triangle-triangle test that the brute-force
// contact baseline of the benchmark uses. Diagnostic code: allocates, not per frame.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vistel {

// Whether two triangles intersect (an edge of one crosses the other; coplanar overlaps
// are not counted). Triangles sharing a vertex should be skipped by the caller.
bool trianglesIntersect(const glm::vec3& a0, const glm::vec3& a1, const glm::vec3& a2,
                        const glm::vec3& b0, const glm::vec3& b1, const glm::vec3& b2);

// Faces whose normal in `deformed` points against their normal in `reference` (e.g. the
// rigidly skinned mesh).
int countInvertedFaces(std::span<const glm::vec3> reference, std::span<const glm::vec3> deformed,
                       std::span<const std::uint32_t> indices);

// Pairs of faces that intersect, among faces that share no vertex. faces: the subset to
// check (empty: all). Uniform-grid broad phase; O(n) for well-spread meshes.
int countSelfIntersections(std::span<const glm::vec3> positions,
                           std::span<const std::uint32_t> indices,
                           std::span<const std::uint32_t> faces = {});

// Closest point on triangle abc to p.
glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b,
                                 const glm::vec3& c);

// Generalized winding number of a triangle mesh at p (sum of signed solid angles over
// 4 pi): ~1 inside a closed outward mesh, ~0 outside, ~0.5 on its surface, ~1.5 for a
// surface point that lies inside another part of the same mesh.
double windingNumber(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                     const glm::vec3& p);

// Deepest penetration (m) of the given vertices into the part made of `faces`: a vertex
// lies inside when it is behind its nearest partner face (within max_distance) and the
// winding number of the whole (closed) mesh there exceeds 1 (inside another part); its
// depth is the distance to that face. Vertices farther than max_distance from every
// partner face, or deeper than the partner's medial axis, are not seen. O(vertices x
// triangles); for tests and tools.
float penetrationDepth(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                       std::span<const std::uint32_t> faces,
                       std::span<const std::uint32_t> vertices, float max_distance);

}  // namespace vistel
