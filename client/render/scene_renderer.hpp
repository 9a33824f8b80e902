// Draws the room: a box-filtered checker floor that fades into the background, lit skin
// (hemisphere ambient + one directional key light + a faint highlight), and marker
// diamonds. Colours are linear 0..1 RGB written straight to an RGBA8 target.
#pragma once

#include <span>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "client/render/camera.hpp"
#include "client/render/gpu_mesh.hpp"
#include "client/render/gpu_skin_mesh.hpp"
#include "common/base/result.hpp"
#include "common/math/dual_quat.hpp"

namespace vistel {

inline constexpr glm::vec3 kBackgroundColor{0.10f, 0.11f, 0.14f};
inline constexpr glm::vec3 kSkinColor{0.90f, 0.70f, 0.58f};

// Member colours for markers and name tags (cycled by member index), and the skin tint
// derived from one (a mild multiplicative tint that keeps the skin skin-coloured).
glm::vec3 memberColor(int index);
glm::vec3 tintedSkin(const glm::vec3& member_color);

class SceneRenderer {
 public:
  SceneRenderer() = default;
  ~SceneRenderer();  // needs the context current
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Compiles the programs and builds the floor and marker meshes.
  Status init();

  // Clears colour and depth of the bound framebuffer inside the eye's viewport.
  void clearViewport(const glm::ivec4& viewport, bool color, bool depth) const;
  // The floor plane y = 0 around `center` (room space) out to `extent` metres.
  void drawFloor(const EyeCamera& eye, const glm::vec3& center, float extent) const;
  // Lit meshes: call beginMeshes once per eye, then drawMesh/drawMarker any number of
  // times. model: model -> room (rigid or uniformly scaled).
  void beginMeshes(const EyeCamera& eye) const;
  void drawMesh(const GpuMesh& mesh, const glm::mat4& model, const glm::vec3& color) const;
  // A diamond `size` metres tall centred at p_room.
  void drawMarker(const glm::vec3& p_room, float size, const glm::vec3& color) const;
  // Meshes skinned in the vertex shader: call beginSkinnedMeshes once per eye (after which
  // drawMesh/drawMarker need beginMeshes again), then drawSkinnedMesh any number of times.
  // skin: the joints' dual quaternions, bind -> posed model space (mesh.jointCount() of
  // them; a draw with fewer is skipped); model: model -> room (rigid).
  void beginSkinnedMeshes(const EyeCamera& eye) const;
  // with_offsets: add the mesh's uploaded offsets (GpuSkinMesh::uploadOffsets).
  void drawSkinnedMesh(const GpuSkinMesh& mesh, std::span<const DualQuat> skin,
                       const glm::mat4& model, const glm::vec3& color,
                       bool with_offsets = false) const;

 private:
  GLuint skin_program_ = 0;
  GLint skin_model_ = -1;
  GLint skin_view_proj_ = -1;
  GLint skin_normal_matrix_ = -1;
  GLint skin_color_ = -1;
  GLint skin_eye_ = -1;
  GLint skin_light_ = -1;
  GLuint gpu_skin_program_ = 0;
  GLint gpu_skin_model_ = -1;
  GLint gpu_skin_view_proj_ = -1;
  GLint gpu_skin_normal_matrix_ = -1;
  GLint gpu_skin_color_ = -1;
  GLint gpu_skin_eye_ = -1;
  GLint gpu_skin_light_ = -1;
  GLint gpu_skin_joints_ = -1;
  GLuint floor_program_ = 0;
  GLint floor_view_proj_ = -1;
  GLint floor_center_ = -1;
  GLint floor_extent_ = -1;
  GLint floor_background_ = -1;
  GLuint floor_vao_ = 0;
  GpuMesh marker_;
};

}  // namespace vistel
