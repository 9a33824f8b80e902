// Name tags drawn in screen space: a translucent box in the member's colour with the
// name in white, built from stb_easy_font's quads (Debian's libstb, header-only part).
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

class LabelRenderer {
 public:
  static constexpr int kMaxQuads = 16384;       // per draw() call; more are dropped
  static constexpr std::size_t kMaxChars = 40;  // longer names are cut

  LabelRenderer() = default;
  ~LabelRenderer();  // needs the context current
  LabelRenderer(const LabelRenderer&) = delete;
  LabelRenderer& operator=(const LabelRenderer&) = delete;

  Status init();

  // Queues a tag whose bottom centre sits at anchor (pixels inside the viewport, origin
  // top-left). scale: pixels per font unit (the font is about 7 units tall).
  void add(const glm::vec2& anchor, std::string_view text, const glm::vec3& color, float scale);
  // Draws the queued tags over the viewport (no depth test) and empties the queue.
  void draw(const glm::ivec4& viewport);

 private:
  struct Vertex {
    float x, y, z;
    std::uint8_t rgba[4];
  };
  void addQuad(float x0, float y0, float x1, float y1, const std::uint8_t rgba[4]);

  std::vector<Vertex> vertices_;  // queued quads, 4 per quad (capacity kMaxQuads * 4)
  std::vector<char> scratch_;     // stb_easy_font output for one tag
  GLuint program_ = 0;
  GLint screen_ = -1;
  GLuint vao_ = 0;
  GLuint vbo_ = 0;
  GLuint ebo_ = 0;
};

}  // namespace vistel
