// A skinned mesh that the GPU poses itself (issue 19: rigid skinning in the vertex shader
// for bodies the deformable component leaves rigid): the bind-pose positions and normals,
// up to four joint indices and weights per vertex, and the triangles, uploaded once. Each
// frame only the joints' dual quaternions go to the GPU (SceneRenderer::drawSkinnedMesh),
// so the CPU neither skins nor uploads vertices. Dual-quaternion skinning as the CPU path
// (skinDualQuaternion, Kavan et al. 2007): the same blend in the first influence's
// hemisphere, renormalised. Optionally, per-vertex model-space offsets added after skinning
// (a body deformed at a lower rate, drawn between its deformations with the offsets of the
// last one), uploaded only when they change.
#pragma once

#include <cstdint>
#include <span>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "common/anim/skin_mesh.hpp"
#include "common/base/result.hpp"

namespace vistel {

// Joints a GPU-skinned avatar may have (two vec4 uniforms each: 192 of the 256 vec4 that
// GL 3.3 guarantees a vertex shader).
inline constexpr int kMaxGpuSkinJoints = 96;

class GpuSkinMesh {
 public:
  GpuSkinMesh() = default;
  ~GpuSkinMesh();  // needs the context current when created
  GpuSkinMesh(const GpuSkinMesh&) = delete;
  GpuSkinMesh& operator=(const GpuSkinMesh&) = delete;

  // Whether a mesh of this avatar can be skinned on the GPU: at most 4 influences per
  // vertex and at most kMaxGpuSkinJoints joints. No GL.
  static bool supports(const SkinMesh& mesh, int joint_count);
  // Uploads the mesh (a valid SkinMesh, see validateSkinMesh). Fails, leaving it empty,
  // when !supports(). Replaces any previous contents.
  Status create(const SkinMesh& mesh, int joint_count);
  // Replaces the offsets (model space, nvert each: added to the skinned position and to
  // the skinned normal before it is normalised). Spans of the wrong size are ignored.
  void uploadOffsets(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals);
  // Draws the triangles with the currently bound program (attributes 0 = position,
  // 1 = normal, 2 = joints (uvec4), 3 = weights, 4 = position offset, 5 = normal offset),
  // with the uploaded offsets or with none.
  void draw(bool with_offsets) const;
  // Fixed texture coordinates (nvert of them; others ignored) as attribute 6.
  void attachUvs(std::span<const glm::vec2> uvs);
  // As draw, for indices [first, first + count) only (clamped to the mesh's).
  void drawRange(bool with_offsets, std::uint32_t first, std::uint32_t count) const;

  bool empty() const { return vao_ == 0; }
  int jointCount() const { return joint_count_; }

 private:
  void release();

  GLuint vao_ = 0;
  // positions, normals, joints, weights, indices, position offsets, normal offsets
  GLuint buffers_[7] = {0, 0, 0, 0, 0, 0, 0};
  GLuint uvs_ = 0;  // texture coordinates (attachUvs)
  GLsizei index_count_ = 0;
  int vertex_count_ = 0;
  int joint_count_ = 0;
};

}  // namespace vistel
