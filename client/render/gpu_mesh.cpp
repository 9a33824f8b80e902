#include "client/render/gpu_mesh.hpp"

#include "client/render/gpu_look.hpp"

#include <algorithm>
#include <cassert>
#include <cstdint>

namespace vistel {

GpuMesh::~GpuMesh() { release(); }

void GpuMesh::release() {
  if (vao_ == 0) return;
  const GLuint buffers[] = {positions_, normals_, indices_, uvs_};
  glDeleteBuffers(uvs_ != 0 ? 4 : 3, buffers);
  glDeleteVertexArrays(1, &vao_);
  vao_ = positions_ = normals_ = indices_ = uvs_ = 0;
  vertex_count_ = 0;
  index_count_ = 0;
}

void GpuMesh::create(int vertex_count, std::span<const std::uint32_t> indices) {
  release();
  vertex_count_ = vertex_count;
  index_count_ = static_cast<GLsizei>(indices.size());
  const auto bytes =
      static_cast<GLsizeiptr>(sizeof(glm::vec3) * static_cast<std::size_t>(vertex_count));
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  // Two dynamic attribute streams, refilled every frame.
  glGenBuffers(1, &positions_);
  glBindBuffer(GL_ARRAY_BUFFER, positions_);
  glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_DYNAMIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  glEnableVertexAttribArray(0);
  glGenBuffers(1, &normals_);
  glBindBuffer(GL_ARRAY_BUFFER, normals_);
  glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_DYNAMIC_DRAW);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  glEnableVertexAttribArray(1);
  // Fixed triangles.
  glGenBuffers(1, &indices_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indices_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void GpuMesh::upload(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals) {
  assert(static_cast<int>(positions.size()) == vertex_count_);
  assert(static_cast<int>(normals.size()) == vertex_count_);
  const auto bytes = static_cast<GLsizeiptr>(positions.size() * sizeof(glm::vec3));
  // Orphan then fill, so the driver need not wait for last frame's draw.
  glBindBuffer(GL_ARRAY_BUFFER, positions_);
  glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_DYNAMIC_DRAW);
  glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, positions.data());
  glBindBuffer(GL_ARRAY_BUFFER, normals_);
  glBufferData(GL_ARRAY_BUFFER, bytes, nullptr, GL_DYNAMIC_DRAW);
  glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, normals.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void GpuMesh::attachUvs(std::span<const glm::vec2> uvs) {
  if (vao_ == 0 || static_cast<int>(uvs.size()) != vertex_count_) return;
  attachUvAttribute(vao_, uvs_, uvs);
}

void GpuMesh::drawRange(std::uint32_t first, std::uint32_t count) const {
  const auto total = static_cast<std::uint32_t>(index_count_);
  if (vao_ == 0 || first >= total) return;
  count = std::min(count, total - first);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                 reinterpret_cast<const void*>(std::uintptr_t{first} * sizeof(std::uint32_t)));
  glBindVertexArray(0);
}

void GpuMesh::draw() const {
  if (vao_ == 0 || index_count_ == 0) return;
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
}

}  // namespace vistel
