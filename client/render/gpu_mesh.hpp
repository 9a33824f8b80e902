// A triangle mesh on the GPU whose positions and normals are re-uploaded every frame
// (skinned avatars) and whose triangles are fixed.
#pragma once

#include <cstdint>
#include <span>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

namespace vistel {

class GpuMesh {
 public:
  GpuMesh() = default;
  ~GpuMesh();  // needs the context current
  GpuMesh(const GpuMesh&) = delete;
  GpuMesh& operator=(const GpuMesh&) = delete;

  // Allocates buffers for vertex_count vertices and uploads the triangles (3 * ntri
  // indices, each < vertex_count). Replaces any previous contents.
  void create(int vertex_count, std::span<const std::uint32_t> indices);
  // Uploads positions and normals (vertex_count each; model space). No allocation.
  void upload(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals);
  // Draws the triangles with the currently bound program (attributes 0 = position,
  // 1 = normal, and 6 = texture coordinates once attachUvs was called).
  void draw() const;
  // Fixed texture coordinates (vertex_count of them; others ignored) as attribute 6.
  void attachUvs(std::span<const glm::vec2> uvs);
  // Draws indices [first, first + count) of the triangles (clamped to the mesh's).
  void drawRange(std::uint32_t first, std::uint32_t count) const;

  bool empty() const { return vao_ == 0; }
  int vertexCount() const { return vertex_count_; }

 private:
  void release();

  GLuint vao_ = 0;
  GLuint positions_ = 0;
  GLuint normals_ = 0;
  GLuint indices_ = 0;
  GLuint uvs_ = 0;
  int vertex_count_ = 0;
  GLsizei index_count_ = 0;
};

}  // namespace vistel
