#include "client/render/label_renderer.hpp"

#include <algorithm>
#include <cstring>

#include <stb_easy_font.h>

#include "client/render/gl_util.hpp"

namespace vistel {

namespace {

constexpr const char* kLabelVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;  // pixels, origin top-left of the viewport
layout(location = 1) in vec4 a_color;
uniform vec2 u_screen;                    // viewport size, pixels
out vec4 v_color;
void main() {
  v_color = a_color;
  gl_Position = vec4(a_position.x / u_screen.x * 2.0 - 1.0, 1.0 - a_position.y / u_screen.y * 2.0,
                     0.0, 1.0);
}
)";

constexpr const char* kLabelFragment = R"(#version 330 core
in vec4 v_color;
out vec4 o_color;
// Colours are display values; the target is sRGB (linear light in, encoded on write).
vec3 toLinear(vec3 c) {
  return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
void main() { o_color = vec4(toLinear(v_color.rgb), v_color.a); }
)";

std::uint8_t toByte(float v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f);
}

}  // namespace

LabelRenderer::~LabelRenderer() {
  if (program_ != 0) glDeleteProgram(program_);
  if (vao_ != 0) glDeleteVertexArrays(1, &vao_);
  if (vbo_ != 0) glDeleteBuffers(1, &vbo_);
  if (ebo_ != 0) glDeleteBuffers(1, &ebo_);
}

Status LabelRenderer::init() {
  auto program = buildProgram("label", kLabelVertex, kLabelFragment);
  if (!program) return program.error();
  program_ = *program;
  screen_ = uniformLocation(program_, "u_screen");
  vertices_.reserve(static_cast<std::size_t>(kMaxQuads) * 4);
  scratch_.resize(kMaxChars * 400);

  // Quads as indexed triangles: (0 1 2) (0 2 3) for every quad.
  std::vector<std::uint32_t> indices(static_cast<std::size_t>(kMaxQuads) * 6);
  for (std::uint32_t q = 0; q < static_cast<std::uint32_t>(kMaxQuads); ++q) {
    const std::uint32_t quad[6] = {4 * q, 4 * q + 1, 4 * q + 2, 4 * q, 4 * q + 2, 4 * q + 3};
    std::copy(quad, quad + 6, indices.begin() + 6 * q);
  }
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(sizeof(Vertex) * kMaxQuads * 4), nullptr,
               GL_STREAM_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(Vertex),
                        reinterpret_cast<const void*>(offsetof(Vertex, rgba)));
  glEnableVertexAttribArray(1);
  glGenBuffers(1, &ebo_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * 4), indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  return {};
}

void LabelRenderer::addQuad(float x0, float y0, float x1, float y1, const std::uint8_t rgba[4]) {
  if (vertices_.size() + 4 > vertices_.capacity()) return;
  const float xs[4] = {x0, x1, x1, x0};
  const float ys[4] = {y0, y0, y1, y1};
  for (int i = 0; i < 4; ++i) {
    vertices_.push_back(Vertex{xs[i], ys[i], 0.0f, {rgba[0], rgba[1], rgba[2], rgba[3]}});
  }
}

void LabelRenderer::add(const glm::vec2& anchor, std::string_view text, const glm::vec3& color,
                        float scale) {
  // stb_easy_font wants a mutable, NUL-terminated string.
  char buffer[kMaxChars + 1];
  const std::size_t n = std::min(text.size(), kMaxChars);
  std::memcpy(buffer, text.data(), n);
  buffer[n] = '\0';
  for (std::size_t i = 0; i < n; ++i) {
    if (buffer[i] == '\n' || static_cast<unsigned char>(buffer[i]) >= 127) buffer[i] = '?';
  }
  const float text_w = static_cast<float>(stb_easy_font_width(buffer)) * scale;
  const float text_h = 7.0f * scale;
  const float pad = 2.0f * scale;

  // The box, its bottom centre at the anchor.
  const float left = std::round(anchor.x - text_w * 0.5f);
  const float top = anchor.y - text_h - 2.0f * pad;
  const std::uint8_t box[4] = {toByte(color.r * 0.8f), toByte(color.g * 0.8f),
                               toByte(color.b * 0.8f), 200};
  addQuad(left - pad, top, left + text_w + pad, anchor.y, box);

  // The text, scaled about the box's inner corner.
  unsigned char white[4] = {255, 255, 255, 255};
  const int quads = stb_easy_font_print(0.0f, 0.0f, buffer, white, scratch_.data(),
                                        static_cast<int>(scratch_.size()));
  static_assert(sizeof(Vertex) == 16, "stb_easy_font's vertex layout");
  for (int q = 0; q < quads; ++q) {
    if (vertices_.size() + 4 > vertices_.capacity()) break;
    for (int c = 0; c < 4; ++c) {
      Vertex v;
      std::memcpy(&v, scratch_.data() + static_cast<std::size_t>(4 * q + c) * sizeof(Vertex),
                  sizeof(Vertex));
      v.x = left + v.x * scale;
      v.y = top + pad + v.y * scale;
      vertices_.push_back(v);
    }
  }
}

void LabelRenderer::draw(const glm::ivec4& viewport) {
  if (vertices_.empty()) return;
  glViewport(viewport.x, viewport.y, viewport.z, viewport.w);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(program_);
  glUniform2f(screen_, static_cast<float>(viewport.z), static_cast<float>(viewport.w));
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(vertices_.size() * sizeof(Vertex)),
                  vertices_.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(vertices_.size() / 4 * 6), GL_UNSIGNED_INT,
                 nullptr);
  glBindVertexArray(0);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  vertices_.clear();
}

}  // namespace vistel
