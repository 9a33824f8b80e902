#include "render_checks.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::test {

bool isSkin(const std::uint8_t* p) {
  const int r = p[0], g = p[1], b = p[2];
  return r >= 50 && r >= g && r >= b + 12;
}

bool isBackdrop(const std::uint8_t* p) {
  const int r = p[0], b = p[2];
  return b + 2 >= r && !isSkin(p);
}

std::vector<std::uint8_t> rasterizeSilhouette(const EyeCamera& eye, int width, int height,
                                              std::span<const glm::vec3> vertices_room,
                                              std::span<const std::uint32_t> indices) {
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
                                 0);
  std::vector<glm::vec2> projected(vertices_room.size());
  for (std::size_t v = 0; v < vertices_room.size(); ++v) {
    glm::vec3 p;
    projectToPixel(eye, vertices_room[v], p);
    projected[v] = glm::vec2(p);
  }
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::vec2 a = projected[indices[t]], b = projected[indices[t + 1]],
                    c = projected[indices[t + 2]];
    const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (std::abs(area) < 1e-9f) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const glm::vec2 p(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
        const float w0 = (b.x - p.x) * (c.y - p.y) - (b.y - p.y) * (c.x - p.x);
        const float w1 = (c.x - p.x) * (a.y - p.y) - (c.y - p.y) * (a.x - p.x);
        const float w2 = (a.x - p.x) * (b.y - p.y) - (a.y - p.y) * (b.x - p.x);
        const bool inside =
            area > 0 ? (w0 >= 0 && w1 >= 0 && w2 >= 0) : (w0 <= 0 && w1 <= 0 && w2 <= 0);
        if (inside) mask[static_cast<std::size_t>((height - 1 - y) * width + x)] = 1;
      }
    }
  }
  return mask;
}

namespace {

std::vector<std::uint8_t> morph(const std::vector<std::uint8_t>& mask, int width, int height, int r,
                                bool all) {
  std::vector<std::uint8_t> out(mask.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      bool any = false;
      bool every = true;
      for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
          const int xx = x + dx, yy = y + dy;
          const bool set = xx >= 0 && yy >= 0 && xx < width && yy < height &&
                           mask[static_cast<std::size_t>(yy * width + xx)] != 0;
          any = any || set;
          every = every && set;
        }
      }
      out[static_cast<std::size_t>(y * width + x)] = (all ? every : any) ? 1 : 0;
    }
  }
  return out;
}

}  // namespace

std::vector<std::uint8_t> erode(const std::vector<std::uint8_t>& mask, int width, int height,
                                int r) {
  return morph(mask, width, height, r, true);
}

std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& mask, int width, int height,
                                 int r) {
  return morph(mask, width, height, r, false);
}

bool pixelOf(const EyeCamera& eye, int height, const glm::vec3& p_room, int& out_x, int& out_row) {
  glm::vec3 p;
  if (!projectToPixel(eye, p_room, p)) return false;
  out_x = static_cast<int>(std::floor(p.x));
  out_row = height - 1 - static_cast<int>(std::floor(p.y));
  return true;
}

}  // namespace vistel::test
