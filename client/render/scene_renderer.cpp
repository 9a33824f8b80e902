#include "client/render/scene_renderer.hpp"

#include <array>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "client/render/gl_util.hpp"

namespace vistel {

namespace {

constexpr const char* kSkinVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform mat3 u_normal_matrix;
out vec3 v_world;
out vec3 v_normal;
void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_world = world.xyz;
  v_normal = u_normal_matrix * a_normal;
  gl_Position = u_view_proj * world;
}
)";

// Dual-quaternion skinning (Kavan et al. 2007) of the bind pose, as skinDualQuaternion on
// the CPU: blend in the first influence's hemisphere, normalise, rotate, translate.
// u_dq[2 j] is joint j's real part, u_dq[2 j + 1] its dual part (x, y, z, w). Then the
// optional model-space offsets (zero when their arrays are off).
constexpr const char* kGpuSkinVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in uvec4 a_joints;
layout(location = 3) in vec4 a_weights;
layout(location = 4) in vec3 a_offset;
layout(location = 5) in vec3 a_normal_offset;
uniform mat4 u_model;
uniform mat4 u_view_proj;
uniform mat3 u_normal_matrix;
uniform vec4 u_dq[192];
out vec3 v_world;
out vec3 v_normal;
vec3 rotate(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }
void main() {
  vec4 pivot = u_dq[2u * a_joints.x];
  vec4 real = vec4(0.0);
  vec4 dual = vec4(0.0);
  for (int s = 0; s < 4; ++s) {
    float w = a_weights[s];
    if (w <= 0.0) continue;
    uint j = a_joints[s];
    vec4 r = u_dq[2u * j];
    float signed_w = dot(r, pivot) < 0.0 ? -w : w;
    real += r * signed_w;
    dual += u_dq[2u * j + 1u] * signed_w;
  }
  float len = length(real);
  real /= len;
  dual /= len;
  dual -= real * dot(real, dual);
  vec3 t = 2.0 * (real.w * dual.xyz - dual.w * real.xyz + cross(real.xyz, dual.xyz));
  vec3 p_model = rotate(real, a_position) + t + a_offset;
  vec4 world = u_model * vec4(p_model, 1.0);
  v_world = world.xyz;
  v_normal = u_normal_matrix * normalize(rotate(real, a_normal) + a_normal_offset);
  gl_Position = u_view_proj * world;
}
)";

constexpr const char* kSkinFragment = R"(#version 330 core
in vec3 v_world;
in vec3 v_normal;
uniform vec3 u_color;
uniform vec3 u_eye;
uniform vec3 u_light;  // unit direction towards the light
out vec4 o_color;
void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  // Hemisphere ambient: warm ground bounce below, cool sky above.
  vec3 ambient = mix(vec3(0.30, 0.27, 0.25), vec3(0.50, 0.53, 0.58), 0.5 + 0.5 * n.y);
  float diffuse = max(dot(n, u_light), 0.0);
  vec3 v = normalize(u_eye - v_world);
  vec3 h = normalize(v + u_light);
  float highlight = 0.06 * pow(max(dot(n, h), 0.0), 24.0);
  vec3 c = u_color * (ambient + 0.70 * diffuse * vec3(1.0, 0.97, 0.92)) + vec3(highlight);
  o_color = vec4(min(c, vec3(1.0)), 1.0);
}
)";

constexpr const char* kFloorVertex = R"(#version 330 core
layout(location = 0) in vec2 a_corner;
uniform mat4 u_view_proj;
uniform vec3 u_center;
uniform float u_extent;
out vec3 v_world;
void main() {
  v_world = vec3(u_center.x + a_corner.x * u_extent, 0.0, u_center.z + a_corner.y * u_extent);
  gl_Position = u_view_proj * vec4(v_world, 1.0);
}
)";

// Box-filtered checker (the analytic integral of the checker over the pixel footprint),
// so the far floor greys out instead of shimmering; then fades into the background.
constexpr const char* kFloorFragment = R"(#version 330 core
in vec3 v_world;
uniform vec3 u_center;
uniform float u_extent;
uniform vec3 u_background;
out vec4 o_color;
void main() {
  vec2 p = v_world.xz / 0.5;
  vec2 w = fwidth(p) + 1e-4;
  vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
  float checker = 0.5 - 0.5 * i.x * i.y;
  vec3 c = mix(vec3(0.24, 0.26, 0.30), vec3(0.34, 0.36, 0.41), checker);
  float d = length(v_world.xz - u_center.xz);
  c = mix(c, u_background, smoothstep(0.45 * u_extent, u_extent, d));
  o_color = vec4(c, 1.0);
}
)";

// An octahedron with flat face normals (24 vertices), unit height, centred at 0.
void buildDiamond(std::array<glm::vec3, 24>& positions, std::array<glm::vec3, 24>& normals) {
  const glm::vec3 top(0, 0.5f, 0), bottom(0, -0.5f, 0);
  const glm::vec3 ring[4] = {{0.3f, 0, 0}, {0, 0, -0.3f}, {-0.3f, 0, 0}, {0, 0, 0.3f}};
  int v = 0;
  for (int k = 0; k < 4; ++k) {
    const glm::vec3 a = ring[k], b = ring[(k + 1) % 4];
    const glm::vec3 up_tri[3] = {a, b, top};
    const glm::vec3 down_tri[3] = {b, a, bottom};
    for (const auto* tri : {up_tri, down_tri}) {
      const glm::vec3 n = glm::normalize(glm::cross(tri[1] - tri[0], tri[2] - tri[0]));
      for (int c = 0; c < 3; ++c) {
        positions[static_cast<std::size_t>(v)] = tri[c];
        normals[static_cast<std::size_t>(v)] = n;
        ++v;
      }
    }
  }
}

// Key light from above, in front and to the side (room space): unit direction towards it.
glm::vec3 keyLight() { return glm::normalize(glm::vec3(0.4f, 0.8f, 0.45f)); }

}  // namespace

glm::vec3 memberColor(int index) {
  static constexpr std::array<glm::vec3, 8> kPalette = {
      glm::vec3(0.95f, 0.55f, 0.15f), glm::vec3(0.20f, 0.60f, 0.95f),
      glm::vec3(0.35f, 0.85f, 0.35f), glm::vec3(0.90f, 0.30f, 0.55f),
      glm::vec3(0.95f, 0.85f, 0.20f), glm::vec3(0.60f, 0.40f, 0.95f),
      glm::vec3(0.25f, 0.85f, 0.80f), glm::vec3(0.95f, 0.35f, 0.30f)};
  const auto n = static_cast<int>(kPalette.size());
  return kPalette[static_cast<std::size_t>(((index % n) + n) % n)];
}

glm::vec3 tintedSkin(const glm::vec3& member_color) {
  return kSkinColor * glm::mix(glm::vec3(1.0f), member_color, 0.3f) * 1.15f;
}

SceneRenderer::~SceneRenderer() {
  if (skin_program_ != 0) glDeleteProgram(skin_program_);
  if (gpu_skin_program_ != 0) glDeleteProgram(gpu_skin_program_);
  if (floor_program_ != 0) glDeleteProgram(floor_program_);
  if (floor_vao_ != 0) glDeleteVertexArrays(1, &floor_vao_);
}

Status SceneRenderer::init() {
  auto skin = buildProgram("skin", kSkinVertex, kSkinFragment);
  if (!skin) return skin.error();
  skin_program_ = *skin;
  skin_model_ = uniformLocation(skin_program_, "u_model");
  skin_view_proj_ = uniformLocation(skin_program_, "u_view_proj");
  skin_normal_matrix_ = uniformLocation(skin_program_, "u_normal_matrix");
  skin_color_ = uniformLocation(skin_program_, "u_color");
  skin_eye_ = uniformLocation(skin_program_, "u_eye");
  skin_light_ = uniformLocation(skin_program_, "u_light");

  auto gpu_skin = buildProgram("gpu skin", kGpuSkinVertex, kSkinFragment);
  if (!gpu_skin) return gpu_skin.error();
  gpu_skin_program_ = *gpu_skin;
  gpu_skin_model_ = uniformLocation(gpu_skin_program_, "u_model");
  gpu_skin_view_proj_ = uniformLocation(gpu_skin_program_, "u_view_proj");
  gpu_skin_normal_matrix_ = uniformLocation(gpu_skin_program_, "u_normal_matrix");
  gpu_skin_color_ = uniformLocation(gpu_skin_program_, "u_color");
  gpu_skin_eye_ = uniformLocation(gpu_skin_program_, "u_eye");
  gpu_skin_light_ = uniformLocation(gpu_skin_program_, "u_light");
  gpu_skin_joints_ = uniformLocation(gpu_skin_program_, "u_dq");

  auto floor = buildProgram("floor", kFloorVertex, kFloorFragment);
  if (!floor) return floor.error();
  floor_program_ = *floor;
  floor_view_proj_ = uniformLocation(floor_program_, "u_view_proj");
  floor_center_ = uniformLocation(floor_program_, "u_center");
  floor_extent_ = uniformLocation(floor_program_, "u_extent");
  floor_background_ = uniformLocation(floor_program_, "u_background");

  // The floor: one quad as a triangle strip from a tiny static buffer owned by the VAO.
  static constexpr float kCorners[] = {-1, -1, -1, 1, 1, -1, 1, 1};
  glGenVertexArrays(1, &floor_vao_);
  glBindVertexArray(floor_vao_);
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, sizeof(kCorners), kCorners, GL_STATIC_DRAW);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glBindVertexArray(0);
  glDeleteBuffers(1, &buffer);  // stays alive while the VAO references it

  // The marker diamond.
  std::array<glm::vec3, 24> positions;
  std::array<glm::vec3, 24> normals;
  buildDiamond(positions, normals);
  std::array<std::uint32_t, 24> indices;
  for (std::uint32_t i = 0; i < 24; ++i) indices[i] = i;
  marker_.create(24, indices);
  marker_.upload(positions, normals);
  return {};
}

void SceneRenderer::clearViewport(const glm::ivec4& viewport, bool color, bool depth) const {
  glEnable(GL_SCISSOR_TEST);
  glScissor(viewport.x, viewport.y, viewport.z, viewport.w);
  glClearColor(kBackgroundColor.r, kBackgroundColor.g, kBackgroundColor.b, 1.0f);
  glClearDepth(1.0);
  glClear((color ? GL_COLOR_BUFFER_BIT : 0u) | (depth ? GL_DEPTH_BUFFER_BIT : 0u));
  glDisable(GL_SCISSOR_TEST);
}

void SceneRenderer::drawFloor(const EyeCamera& eye, const glm::vec3& center, float extent) const {
  glViewport(eye.viewport.x, eye.viewport.y, eye.viewport.z, eye.viewport.w);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glUseProgram(floor_program_);
  const glm::mat4 view_proj = eye.projection * eye.view;
  glUniformMatrix4fv(floor_view_proj_, 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform3fv(floor_center_, 1, glm::value_ptr(center));
  glUniform1f(floor_extent_, extent);
  glUniform3fv(floor_background_, 1, glm::value_ptr(kBackgroundColor));
  // Pull the floor slightly back in depth so soles standing on it win.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  glBindVertexArray(floor_vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glBindVertexArray(0);
  glDisable(GL_POLYGON_OFFSET_FILL);
}

void SceneRenderer::beginMeshes(const EyeCamera& eye) const {
  glViewport(eye.viewport.x, eye.viewport.y, eye.viewport.z, eye.viewport.w);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  glUseProgram(skin_program_);
  const glm::mat4 view_proj = eye.projection * eye.view;
  glUniformMatrix4fv(skin_view_proj_, 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform3fv(skin_eye_, 1, glm::value_ptr(eye.position));
  glUniform3fv(skin_light_, 1, glm::value_ptr(keyLight()));
}

void SceneRenderer::drawMesh(const GpuMesh& mesh, const glm::mat4& model,
                             const glm::vec3& color) const {
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(model)));
  glUniformMatrix4fv(skin_model_, 1, GL_FALSE, glm::value_ptr(model));
  glUniformMatrix3fv(skin_normal_matrix_, 1, GL_FALSE, glm::value_ptr(normal_matrix));
  glUniform3fv(skin_color_, 1, glm::value_ptr(color));
  mesh.draw();
}

void SceneRenderer::beginSkinnedMeshes(const EyeCamera& eye) const {
  beginMeshes(eye);
  glUseProgram(gpu_skin_program_);
  const glm::mat4 view_proj = eye.projection * eye.view;
  glUniformMatrix4fv(gpu_skin_view_proj_, 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform3fv(gpu_skin_eye_, 1, glm::value_ptr(eye.position));
  glUniform3fv(gpu_skin_light_, 1, glm::value_ptr(keyLight()));
}

void SceneRenderer::drawSkinnedMesh(const GpuSkinMesh& mesh, std::span<const DualQuat> skin,
                                    const glm::mat4& model, const glm::vec3& color,
                                    bool with_offsets) const {
  static_assert(sizeof(DualQuat) == 8 * sizeof(float), "two vec4 per joint");
  const int joints = mesh.jointCount();
  if (mesh.empty() || joints > kMaxGpuSkinJoints || static_cast<int>(skin.size()) < joints) {
    return;
  }
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(model)));
  glUniformMatrix4fv(gpu_skin_model_, 1, GL_FALSE, glm::value_ptr(model));
  glUniformMatrix3fv(gpu_skin_normal_matrix_, 1, GL_FALSE, glm::value_ptr(normal_matrix));
  glUniform3fv(gpu_skin_color_, 1, glm::value_ptr(color));
  glUniform4fv(gpu_skin_joints_, 2 * joints, &skin[0].real.x);
  mesh.draw(with_offsets);
}

void SceneRenderer::drawMarker(const glm::vec3& p_room, float size, const glm::vec3& color) const {
  const glm::mat4 model = glm::scale(glm::translate(glm::mat4(1.0f), p_room), glm::vec3(size));
  drawMesh(marker_, model, color);
}

}  // namespace vistel
