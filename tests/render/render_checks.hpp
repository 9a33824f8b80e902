// Helpers for render tests: colour classes, a CPU silhouette rasteriser, and making a
// view that skips the test only when no OpenGL exists at all.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "client/render/camera.hpp"
#include "client/render/image.hpp"

namespace vistel::test {

// Skin: warm (red above blue and at least green), not too dark.
bool isSkin(const std::uint8_t* rgba);
// Background or floor: cool grey (blue at least red), never skin.
bool isBackdrop(const std::uint8_t* rgba);

// A coverage mask (width * height, rows from the top like Image) of triangles
// (room-space vertices, indices) projected through `eye`; pixel centres are sampled.
std::vector<std::uint8_t> rasterizeSilhouette(const EyeCamera& eye, int width, int height,
                                              std::span<const glm::vec3> vertices_room,
                                              std::span<const std::uint32_t> indices);

// Pixels whose whole (2r+1)^2 neighbourhood is set (erode) or where any is set (dilate).
std::vector<std::uint8_t> erode(const std::vector<std::uint8_t>& mask, int width, int height,
                                int r);
std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& mask, int width, int height,
                                 int r);

// Image row (from the top) and column of a room point, or false when behind the eye.
bool pixelOf(const EyeCamera& eye, int height, const glm::vec3& p_room, int& out_x, int& out_row);

}  // namespace vistel::test

// Creates a RoomView into `var`; skips the test when no OpenGL context can be had at all
// (no display and no EGL), fails it on any other error.
#define VISTEL_MAKE_VIEW(var, options)                                                       \
  auto var##_created = ::vistel::RoomView::create(options);                                  \
  if (!var##_created.ok()) {                                                                 \
    if (var##_created.error().message.find("no OpenGL available") != std::string::npos) {    \
      GTEST_SKIP() << "no OpenGL at all on this machine: " << var##_created.error().message; \
    }                                                                                        \
    FAIL() << var##_created.error().message;                                                 \
  }                                                                                          \
  std::unique_ptr<::vistel::RoomView> var = std::move(*var##_created)
