#include "client/render/scene_renderer.hpp"

#include <array>
#include <cmath>
#include <string>

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
vec3 toLinear(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
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
  // Tuned as display values: written as linear light to the sRGB target.
  o_color = vec4(toLinear(min(c, vec3(1.0))), 1.0);
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
vec3 toLinear(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
void main() {
  vec2 p = v_world.xz / 0.5;
  vec2 w = fwidth(p) + 1e-4;
  vec2 i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
  float checker = 0.5 - 0.5 * i.x * i.y;
  vec3 c = mix(vec3(0.24, 0.26, 0.30), vec3(0.34, 0.36, 0.41), checker);
  float d = length(v_world.xz - u_center.xz);
  c = mix(c, u_background, smoothstep(0.45 * u_extent, u_extent, d));
  o_color = vec4(toLinear(c), 1.0);  // display values, written as linear light
}
)";

// The look's fragment shader: base colour (linear factor x sRGB texture, decoded by the
// sampler), optional normal map (tangent frame from screen-space derivatives, glTF's +Y
// up = towards -v), lighting in linear light, written linear (the sRGB target encodes).
constexpr const char* kLookFragment = R"(#version 330 core
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
uniform vec3 u_eye;
uniform vec3 u_light;  // unit direction towards the light
uniform vec4 u_base_color;
uniform vec3 u_tint;
uniform sampler2D u_base_tex;
uniform sampler2D u_normal_tex;
uniform bool u_has_normal_map;
uniform float u_normal_scale;
uniform float u_alpha_cutoff;  // < 0: opaque
uniform bool u_blend;          // alphaMode BLEND: the alpha goes to blending
out vec4 o_color;
void main() {
  vec4 base = u_base_color * texture(u_base_tex, v_uv);
  if (u_alpha_cutoff >= 0.0 && base.a < u_alpha_cutoff) discard;
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  if (u_has_normal_map) {
    vec3 dp1 = dFdx(v_world);
    vec3 dp2 = dFdy(v_world);
    vec2 duv1 = dFdx(v_uv);
    vec2 duv2 = dFdy(v_uv);
    vec3 dp2perp = cross(dp2, n);
    vec3 dp1perp = cross(n, dp1);
    vec3 t = dp2perp * duv1.x + dp1perp * duv2.x;
    vec3 b = -(dp2perp * duv1.y + dp1perp * duv2.y);
    float len2 = max(dot(t, t), dot(b, b));
    if (len2 > 1e-20) {
      float s = inversesqrt(len2);
      vec3 m = texture(u_normal_tex, v_uv).xyz * 2.0 - 1.0;
      m.xy *= u_normal_scale;
      vec3 mapped = mat3(t * s, b * s, n) * m;
      if (dot(mapped, mapped) > 1e-12) n = normalize(mapped);
    }
  }
  // Linear light: a hemisphere ambient (sky above, ground bounce below) and the key light.
  vec3 ambient = mix(vec3(0.11, 0.095, 0.085), vec3(0.22, 0.24, 0.28), 0.5 + 0.5 * n.y);
  float diffuse = max(dot(n, u_light), 0.0);
  vec3 v = normalize(u_eye - v_world);
  vec3 h = normalize(v + u_light);
  float highlight = 0.03 * pow(max(dot(n, h), 0.0), 32.0);
  vec3 albedo = base.rgb * u_tint;
  vec3 c = albedo * (ambient + 0.85 * diffuse * vec3(1.0, 0.96, 0.90)) + vec3(highlight);
  o_color = vec4(clamp(c, 0.0, 1.0), u_blend ? clamp(base.a, 0.0, 1.0) : 1.0);
}
)";

constexpr const char* kShadowFragment = R"(#version 330 core
uniform float u_alpha;
out vec4 o_color;
// u_alpha darkens the encoded value by (1 - u_alpha); blending is in linear light, where
// that is about (1 - u_alpha)^2.2.
void main() { o_color = vec4(0.0, 0.0, 0.0, 1.0 - pow(1.0 - u_alpha, 2.2)); }
)";

// A vertex shader with texture coordinates passed through (attribute 6).
std::string withUvs(const char* vertex_source) {
  std::string s(vertex_source);
  const std::string decl = "out vec3 v_normal;\n";
  s.replace(s.find(decl), decl.size(),
            decl + "layout(location = 6) in vec2 a_uv;\nout vec2 v_uv;\n");
  const std::string last = "  gl_Position = u_view_proj * world;\n";
  s.replace(s.find(last), last.size(), "  v_uv = a_uv;\n" + last);
  return s;
}

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

// An sRGB-encoded colour in linear light (the exact inverse of GL's encoding).
glm::vec3 srgbToLinear(const glm::vec3& c) {
  glm::vec3 out;
  for (int k = 0; k < 3; ++k) {
    out[k] = c[k] <= 0.04045f ? c[k] / 12.92f : std::pow((c[k] + 0.055f) / 1.055f, 2.4f);
  }
  return out;
}

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
  for (GLuint p : {look_program_.program, gpu_look_program_.program, shadow_program_.program,
                   gpu_shadow_program_.program}) {
    if (p != 0) glDeleteProgram(p);
  }
  for (GLuint t : {white_texture_, flat_normal_texture_}) {
    if (t != 0) glDeleteTextures(1, &t);
  }
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
  return initLook();
}

Status SceneRenderer::initLook() {
  // Optional uniforms (a program may not use every one).
  auto loc = [](GLuint program, const char* name) { return glGetUniformLocation(program, name); };
  auto makeLook = [&](const char* name, const std::string& vertex, LookProgram& out) -> Status {
    auto program = buildProgram(name, vertex.c_str(), kLookFragment);
    if (!program) return program.error();
    out.program = *program;
    out.model = loc(out.program, "u_model");
    out.view_proj = loc(out.program, "u_view_proj");
    out.normal_matrix = loc(out.program, "u_normal_matrix");
    out.eye = loc(out.program, "u_eye");
    out.light = loc(out.program, "u_light");
    out.base_color = loc(out.program, "u_base_color");
    out.tint = loc(out.program, "u_tint");
    out.has_normal_map = loc(out.program, "u_has_normal_map");
    out.normal_scale = loc(out.program, "u_normal_scale");
    out.alpha_cutoff = loc(out.program, "u_alpha_cutoff");
    out.blend = loc(out.program, "u_blend");
    out.joints = loc(out.program, "u_dq");
    glUseProgram(out.program);
    glUniform1i(loc(out.program, "u_base_tex"), 0);
    glUniform1i(loc(out.program, "u_normal_tex"), 1);
    glUseProgram(0);
    return {};
  };
  if (Status s = makeLook("look", withUvs(kSkinVertex), look_program_); !s) return s;
  if (Status s = makeLook("gpu look", withUvs(kGpuSkinVertex), gpu_look_program_); !s) return s;
  auto makeShadow = [&](const char* name, const char* vertex, ShadowProgram& out) -> Status {
    auto program = buildProgram(name, vertex, kShadowFragment);
    if (!program) return program.error();
    out.program = *program;
    out.model = loc(out.program, "u_model");
    out.view_proj = loc(out.program, "u_view_proj");
    out.joints = loc(out.program, "u_dq");
    out.alpha = loc(out.program, "u_alpha");
    return {};
  };
  if (Status s = makeShadow("shadow", kSkinVertex, shadow_program_); !s) return s;
  if (Status s = makeShadow("gpu shadow", kGpuSkinVertex, gpu_shadow_program_); !s) return s;

  // 1x1 stand-ins: white (no base texture), a flat normal (no normal map).
  auto pixel = [](GLenum format, const std::uint8_t(&rgba)[4]) {
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(format), 1, 1, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 rgba);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTexture(GL_TEXTURE_2D, 0);
    return tex;
  };
  white_texture_ = pixel(GL_SRGB8_ALPHA8, {255, 255, 255, 255});
  flat_normal_texture_ = pixel(GL_RGBA8, {128, 128, 255, 255});
  return {};
}

void SceneRenderer::beginLook(const LookProgram& p, const EyeCamera& eye) const {
  beginMeshes(eye);
  glUseProgram(p.program);
  const glm::mat4 view_proj = eye.projection * eye.view;
  glUniformMatrix4fv(p.view_proj, 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform3fv(p.eye, 1, glm::value_ptr(eye.position));
  glUniform3fv(p.light, 1, glm::value_ptr(keyLight()));
}

void SceneRenderer::beginLookMeshes(const EyeCamera& eye) const { beginLook(look_program_, eye); }

void SceneRenderer::beginSkinnedLookMeshes(const EyeCamera& eye) const {
  beginLook(gpu_look_program_, eye);
}

void SceneRenderer::drawLookParts(const LookProgram& p, const GpuLook& look, const glm::mat4& model,
                                  const glm::vec3& tint, const GpuMesh* cpu, const GpuSkinMesh* gpu,
                                  bool with_offsets, LookPass which) const {
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(model)));
  glUniformMatrix4fv(p.model, 1, GL_FALSE, glm::value_ptr(model));
  glUniformMatrix3fv(p.normal_matrix, 1, GL_FALSE, glm::value_ptr(normal_matrix));
  glUniform3fv(p.tint, 1, glm::value_ptr(tint));
  // Opaque and masked parts first, then the blended ones over them (alpha blending in
  // linear light, depth tested but not written, so they never hide what is behind).
  bool any_blend = false;
  for (const GpuLook::Part& part : look.parts()) any_blend = any_blend || part.blend;
  const int first = which == LookPass::kBlended ? 1 : 0;
  const int last = which == LookPass::kOpaque || !any_blend ? 0 : 1;
  for (int pass = first; pass <= last; ++pass) {
    const bool blend_pass = pass == 1;
    glUniform1i(p.blend, blend_pass ? 1 : 0);
    if (blend_pass) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
    }
    for (const GpuLook::Part& part : look.parts()) {
      if (part.blend != blend_pass) continue;
      drawLookPart(p, part, cpu, gpu, with_offsets);
    }
    if (blend_pass) {
      glDepthMask(GL_TRUE);
      glDisable(GL_BLEND);
    }
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

void SceneRenderer::drawLookPart(const LookProgram& p, const GpuLook::Part& part,
                                 const GpuMesh* cpu, const GpuSkinMesh* gpu,
                                 bool with_offsets) const {
  {
    glUniform4fv(p.base_color, 1, glm::value_ptr(part.base_color));
    glUniform1i(p.has_normal_map, part.normal_texture != 0 ? 1 : 0);
    glUniform1f(p.normal_scale, part.normal_scale);
    glUniform1f(p.alpha_cutoff, part.alpha_cutoff);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D,
                  part.normal_texture != 0 ? part.normal_texture : flat_normal_texture_);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, part.base_texture != 0 ? part.base_texture : white_texture_);
    if (part.double_sided) glDisable(GL_CULL_FACE);
    if (cpu != nullptr) {
      cpu->drawRange(part.first_index, part.index_count);
    } else if (gpu != nullptr) {
      gpu->drawRange(with_offsets, part.first_index, part.index_count);
    }
    if (part.double_sided) glEnable(GL_CULL_FACE);
  }
}

void SceneRenderer::drawMeshLook(const GpuMesh& mesh, const GpuLook& look, const glm::mat4& model,
                                 const glm::vec3& tint, LookPass pass) const {
  drawLookParts(look_program_, look, model, tint, &mesh, nullptr, false, pass);
}

void SceneRenderer::drawSkinnedMeshLook(const GpuSkinMesh& mesh, const GpuLook& look,
                                        std::span<const DualQuat> skin, const glm::mat4& model,
                                        const glm::vec3& tint, bool with_offsets,
                                        LookPass pass) const {
  const int joints = mesh.jointCount();
  if (mesh.empty() || joints > kMaxGpuSkinJoints || static_cast<int>(skin.size()) < joints) {
    return;
  }
  glUniform4fv(gpu_look_program_.joints, 2 * joints, &skin[0].real.x);
  drawLookParts(gpu_look_program_, look, model, tint, nullptr, &mesh, with_offsets, pass);
}

glm::mat4 SceneRenderer::shadowProjection(float height) {
  const glm::vec3 l = keyLight();
  const float kx = l.x / l.y;
  const float kz = l.z / l.y;
  glm::mat4 s(1.0f);
  s[1] = glm::vec4(-kx, 0.0f, -kz, 0.0f);                    // y moves x and z along the light
  s[3] = glm::vec4(kx * height, height, kz * height, 1.0f);  // and lands on y = height
  return s;
}

void SceneRenderer::beginShadow(const ShadowProgram& p, const EyeCamera& eye) const {
  glViewport(eye.viewport.x, eye.viewport.y, eye.viewport.z, eye.viewport.w);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_FALSE);
  glDisable(GL_CULL_FACE);
  // Each pixel darkens once, however many flattened triangles cover it: the stencil
  // (cleared inside the viewport) marks it on the first.
  glEnable(GL_SCISSOR_TEST);
  glScissor(eye.viewport.x, eye.viewport.y, eye.viewport.z, eye.viewport.w);
  glClearStencil(0);
  glStencilMask(0xFF);
  glClear(GL_STENCIL_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_STENCIL_TEST);
  glStencilFunc(GL_EQUAL, 0, 0xFF);
  glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(p.program);
  const glm::mat4 view_proj = eye.projection * eye.view;
  glUniformMatrix4fv(p.view_proj, 1, GL_FALSE, glm::value_ptr(view_proj));
  glUniform1f(p.alpha, kShadowAlpha);
}

void SceneRenderer::beginShadows(const EyeCamera& eye) const { beginShadow(shadow_program_, eye); }

void SceneRenderer::beginSkinnedShadows(const EyeCamera& eye) const {
  beginShadow(gpu_shadow_program_, eye);
}

void SceneRenderer::drawMeshShadow(const GpuMesh& mesh, const glm::mat4& model) const {
  const glm::mat4 flat = shadowProjection() * model;
  glUniformMatrix4fv(shadow_program_.model, 1, GL_FALSE, glm::value_ptr(flat));
  mesh.draw();
}

void SceneRenderer::drawSkinnedMeshShadow(const GpuSkinMesh& mesh, std::span<const DualQuat> skin,
                                          const glm::mat4& model, bool with_offsets) const {
  const int joints = mesh.jointCount();
  if (mesh.empty() || joints > kMaxGpuSkinJoints || static_cast<int>(skin.size()) < joints) {
    return;
  }
  const glm::mat4 flat = shadowProjection() * model;
  glUniformMatrix4fv(gpu_shadow_program_.model, 1, GL_FALSE, glm::value_ptr(flat));
  glUniform4fv(gpu_shadow_program_.joints, 2 * joints, &skin[0].real.x);
  mesh.draw(with_offsets);
}

void SceneRenderer::endShadows() const {
  glDisable(GL_BLEND);
  glDisable(GL_STENCIL_TEST);
  glDepthMask(GL_TRUE);
}

void SceneRenderer::clearViewport(const glm::ivec4& viewport, bool color, bool depth) const {
  glEnable(GL_SCISSOR_TEST);
  glScissor(viewport.x, viewport.y, viewport.z, viewport.w);
  // Linear light (GL_FRAMEBUFFER_SRGB converts clear colours too): stored as kBackgroundColor.
  // The linear value of the byte kBackgroundColor was always stored as, so that the
  // encoding gives that byte back exactly.
  const glm::vec3 background = srgbToLinear(glm::round(kBackgroundColor * 255.0f) / 255.0f);
  glClearColor(background.r, background.g, background.b, 1.0f);
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
