// The prototype skin of an avatar, as flat arrays the runtime kernels read: rest
// positions and normals in model space (bind posture), triangles, skin weights.
// (The offline tools build it through OpenMesh; the runtime never sees OpenMesh.)
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

inline constexpr int kMaxInfluences = 8;

struct SkinMesh {
  std::vector<glm::vec3> positions;    // rest position per vertex (nvert), metres
  std::vector<glm::vec3> normals;      // rest unit normal per vertex (nvert)
  std::vector<std::uint32_t> indices;  // triangles, counter-clockwise outward (3 * ntri)
  int influences = 4;                  // influence slots per vertex (k), 1..kMaxInfluences
  std::vector<std::uint16_t> joints;   // joint per slot (nvert * k)
  std::vector<float> weights;          // weight per slot (nvert * k), each vertex sums to 1;
                                       // unused slots have weight 0

  int vertexCount() const { return static_cast<int>(positions.size()); }
  int triangleCount() const { return static_cast<int>(indices.size() / 3); }
};

// Checks sizes, index ranges, finite values, weights in [0,1] summing to 1 (1e-4), and
// joints < joint_count. The message names the first bad vertex or triangle.
Status validateSkinMesh(const SkinMesh& mesh, int joint_count);

// Area-weighted vertex normals of a triangle soup over `positions` (out: nvert).
void computeVertexNormals(std::span<const glm::vec3> positions,
                          std::span<const std::uint32_t> indices, std::span<glm::vec3> out_normals);

// Largest number of non-zero weights on any vertex.
int maxInfluencesUsed(const SkinMesh& mesh);

struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};
Bounds computeBounds(std::span<const glm::vec3> points);

}  // namespace vistel

namespace vistel {
// Signed volume enclosed by a closed, outward-oriented triangle mesh (divergence
// theorem), cubic metres.
double enclosedVolume(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices);
}  // namespace vistel
