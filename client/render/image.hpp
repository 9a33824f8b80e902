// RGBA8 images and PNG output (stb_image_write, Debian's precompiled libstb).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

// An RGBA8 image, rows from the top.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // width * height * 4 bytes

  // Pixel (x, y) with y = 0 the top row; no bounds check beyond an assert.
  const std::uint8_t* pixel(int x, int y) const;
};

// Reverses the row order in place (GL reads rows from the bottom).
void flipRows(Image& image);

enum class PngSpeed { kSmallest, kFastest };

// Encodes and writes a PNG atomically (temporary file + rename). Errors name the path
// and say why (empty image, encoder failure, file system). Main thread only: the
// encoder's compression level is a process-wide setting.
Status writePng(const Image& image, const std::string& path, PngSpeed speed = PngSpeed::kSmallest);

}  // namespace vistel
