#include "client/render/gpu_skin_mesh.hpp"

#include "client/render/gpu_look.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace vistel {

GpuSkinMesh::~GpuSkinMesh() { release(); }

void GpuSkinMesh::release() {
  if (vao_ == 0) return;
  glDeleteBuffers(7, buffers_);
  if (uvs_ != 0) glDeleteBuffers(1, &uvs_);
  uvs_ = 0;
  glDeleteVertexArrays(1, &vao_);
  vao_ = 0;
  for (GLuint& b : buffers_) b = 0;
  index_count_ = 0;
  joint_count_ = 0;
  vertex_count_ = 0;
}

bool GpuSkinMesh::supports(const SkinMesh& mesh, int joint_count) {
  return mesh.influences >= 1 && mesh.influences <= 4 && joint_count >= 1 &&
         joint_count <= kMaxGpuSkinJoints && mesh.vertexCount() > 0;
}

Status GpuSkinMesh::create(const SkinMesh& mesh, int joint_count) {
  release();
  if (!supports(mesh, joint_count)) {
    return fail("GPU skinning: {} influences per vertex and {} joints (at most 4 and {})",
                mesh.influences, joint_count, kMaxGpuSkinJoints);
  }
  // Four slots per vertex: the mesh's, then zero weights.
  const auto nvert = static_cast<std::size_t>(mesh.vertexCount());
  const auto k = static_cast<std::size_t>(mesh.influences);
  std::vector<std::array<std::uint16_t, 4>> joints(nvert, {0, 0, 0, 0});
  std::vector<glm::vec4> weights(nvert, glm::vec4(0.0f));
  for (std::size_t v = 0; v < nvert; ++v) {
    for (std::size_t s = 0; s < k; ++s) {
      joints[v][s] = mesh.joints[v * k + s];
      weights[v][static_cast<glm::length_t>(s)] = mesh.weights[v * k + s];
    }
  }

  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(7, buffers_);
  auto upload = [](GLenum target, GLuint buffer, std::size_t bytes, const void* data) {
    glBindBuffer(target, buffer);
    glBufferData(target, static_cast<GLsizeiptr>(bytes), data, GL_STATIC_DRAW);
  };
  upload(GL_ARRAY_BUFFER, buffers_[0], nvert * sizeof(glm::vec3), mesh.positions.data());
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  glEnableVertexAttribArray(0);
  upload(GL_ARRAY_BUFFER, buffers_[1], nvert * sizeof(glm::vec3), mesh.normals.data());
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  glEnableVertexAttribArray(1);
  upload(GL_ARRAY_BUFFER, buffers_[2], nvert * sizeof(joints[0]), joints.data());
  glVertexAttribIPointer(2, 4, GL_UNSIGNED_SHORT, sizeof(joints[0]), nullptr);
  glEnableVertexAttribArray(2);
  upload(GL_ARRAY_BUFFER, buffers_[3], nvert * sizeof(glm::vec4), weights.data());
  glVertexAttribPointer(3, 4, GL_FLOAT, GL_FALSE, sizeof(glm::vec4), nullptr);
  glEnableVertexAttribArray(3);
  upload(GL_ELEMENT_ARRAY_BUFFER, buffers_[4], mesh.indices.size() * sizeof(std::uint32_t),
         mesh.indices.data());
  // Offsets: zero until uploadOffsets; their arrays are enabled per draw.
  const std::vector<glm::vec3> zeros(nvert, glm::vec3(0.0f));
  upload(GL_ARRAY_BUFFER, buffers_[5], nvert * sizeof(glm::vec3), zeros.data());
  glVertexAttribPointer(4, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  upload(GL_ARRAY_BUFFER, buffers_[6], nvert * sizeof(glm::vec3), zeros.data());
  glVertexAttribPointer(5, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  index_count_ = static_cast<GLsizei>(mesh.indices.size());
  joint_count_ = joint_count;
  vertex_count_ = static_cast<int>(nvert);
  return {};
}

void GpuSkinMesh::uploadOffsets(std::span<const glm::vec3> positions,
                                std::span<const glm::vec3> normals) {
  if (vao_ == 0 || static_cast<int>(positions.size()) != vertex_count_ ||
      static_cast<int>(normals.size()) != vertex_count_) {
    return;
  }
  const auto bytes = static_cast<GLsizeiptr>(positions.size() * sizeof(glm::vec3));
  glBindBuffer(GL_ARRAY_BUFFER, buffers_[5]);
  glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, positions.data());
  glBindBuffer(GL_ARRAY_BUFFER, buffers_[6]);
  glBufferSubData(GL_ARRAY_BUFFER, 0, bytes, normals.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void GpuSkinMesh::attachUvs(std::span<const glm::vec2> uvs) {
  if (vao_ == 0 || static_cast<int>(uvs.size()) != vertex_count_) return;
  attachUvAttribute(vao_, uvs_, uvs);
}

void GpuSkinMesh::draw(bool with_offsets) const {
  drawRange(with_offsets, 0, static_cast<std::uint32_t>(index_count_));
}

void GpuSkinMesh::drawRange(bool with_offsets, std::uint32_t first, std::uint32_t count) const {
  const auto total = static_cast<std::uint32_t>(index_count_);
  if (vao_ == 0 || first >= total) return;
  count = std::min(count, total - first);
  glBindVertexArray(vao_);
  // Without offsets the arrays are off and the attributes read the constant 0.
  for (const GLuint location : {4u, 5u}) {
    if (with_offsets) {
      glEnableVertexAttribArray(location);
    } else {
      glDisableVertexAttribArray(location);
      glVertexAttrib3f(location, 0.0f, 0.0f, 0.0f);
    }
  }
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                 reinterpret_cast<const void*>(std::uintptr_t{first} * sizeof(std::uint32_t)));
  glBindVertexArray(0);
}

}  // namespace vistel
