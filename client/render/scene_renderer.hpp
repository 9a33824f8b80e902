// Draws the room: a box-filtered checker floor that fades into the background, lit skin
// (hemisphere ambient + one directional key light + a faint highlight), and marker
// diamonds. The target is sRGB (RenderTarget: GL_SRGB8_ALPHA8 with GL_FRAMEBUFFER_SRGB on),
// so every shader writes linear light and blending and the MSAA resolve happen in linear
// light; the plain paths above are tuned as display values and converted to linear in
// their shaders (so they store the bytes they always did), and the background clear too.
//
// Avatars with a look (materials, textures: GpuLook) are drawn sRGB-correctly: colour
// textures are sampled from sRGB textures (linear values), factors are linear, lighting
// is computed in linear light and written linear (the target encodes it). Normal maps use
// a tangent frame from screen-space derivatives (no tangents needed). alphaMode MASK
// discards below the cutoff; BLEND parts are drawn after the mesh's other parts, alpha
// blended (in linear light), depth tested but not written. A look draw takes a LookPass:
// kAll draws one mesh's opaque parts then its blended ones; a room draws every mesh's
// kOpaque parts first and then the kBlended parts far to near, so a blended part never
// hides a mesh drawn after it.
//
// Shadows: planar projected shadows of the key light (Blinn 1988): each mesh drawn again,
// flattened onto the floor plane y = 0 along the light, as a translucent dark overlay
// (the target's stencil makes overlapping triangles and avatars darken a pixel once;
// the bound framebuffer needs a stencil buffer, as RenderTarget's has).
#pragma once

#include <span>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "client/render/camera.hpp"
#include "client/render/gpu_look.hpp"
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

  // Textured (look) drawing: beginLookMeshes / beginSkinnedLookMeshes once per eye, then
  // any number of draws of that kind; the mesh must carry the look's texture
  // coordinates (attachUvs) when it has any. tint: multiplies the base colour (linear;
  // white keeps the look as authored). Other draws need their begin call again after.
  // pass: which of the look's parts (LookPass, above).
  enum class LookPass { kAll, kOpaque, kBlended };
  void beginLookMeshes(const EyeCamera& eye) const;
  void drawMeshLook(const GpuMesh& mesh, const GpuLook& look, const glm::mat4& model,
                    const glm::vec3& tint, LookPass pass = LookPass::kAll) const;
  void beginSkinnedLookMeshes(const EyeCamera& eye) const;
  void drawSkinnedMeshLook(const GpuSkinMesh& mesh, const GpuLook& look,
                           std::span<const DualQuat> skin, const glm::mat4& model,
                           const glm::vec3& tint, bool with_offsets = false,
                           LookPass pass = LookPass::kAll) const;

  // Shadows on the floor (y = 0): after drawFloor and before the meshes, beginShadows (or
  // beginSkinnedShadows), any number of shadow draws, then endShadows. The draws take the
  // same arguments as the mesh draws.
  void beginShadows(const EyeCamera& eye) const;
  void drawMeshShadow(const GpuMesh& mesh, const glm::mat4& model) const;
  void beginSkinnedShadows(const EyeCamera& eye) const;
  void drawSkinnedMeshShadow(const GpuSkinMesh& mesh, std::span<const DualQuat> skin,
                             const glm::mat4& model, bool with_offsets = false) const;
  void endShadows() const;
  // The flattening transform (room -> room): a point moved along the key light onto
  // y = height. Exposed for tests.
  static glm::mat4 shadowProjection(float height = kShadowLift);
  static constexpr float kShadowLift = 0.002f;  // metres above the floor
  static constexpr float kShadowAlpha = 0.38f;  // darkening of the floor under a shadow

 private:
  struct LookProgram {
    GLuint program = 0;
    GLint model = -1, view_proj = -1, normal_matrix = -1, eye = -1, light = -1;
    GLint base_color = -1, tint = -1, has_normal_map = -1, normal_scale = -1;
    GLint alpha_cutoff = -1, blend = -1, joints = -1;
  };
  struct ShadowProgram {
    GLuint program = 0;
    GLint model = -1, view_proj = -1, joints = -1, alpha = -1;
  };
  Status initLook();
  void beginLook(const LookProgram& p, const EyeCamera& eye) const;
  // Draws each part of `look` from `cpu` (a GpuMesh) or else `gpu` (a GpuSkinMesh).
  void drawLookParts(const LookProgram& p, const GpuLook& look, const glm::mat4& model,
                     const glm::vec3& tint, const GpuMesh* cpu, const GpuSkinMesh* gpu,
                     bool with_offsets, LookPass which) const;
  void drawLookPart(const LookProgram& p, const GpuLook::Part& part, const GpuMesh* cpu,
                    const GpuSkinMesh* gpu, bool with_offsets) const;
  void beginShadow(const ShadowProgram& p, const EyeCamera& eye) const;

  LookProgram look_program_;
  LookProgram gpu_look_program_;
  ShadowProgram shadow_program_;
  ShadowProgram gpu_shadow_program_;
  GLuint white_texture_ = 0;
  GLuint flat_normal_texture_ = 0;

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
