#include "client/render/image.hpp"

#include <cassert>
#include <cstring>

#include <stb_image_write.h>

#include "common/base/file.hpp"

namespace vistel {

const std::uint8_t* Image::pixel(int x, int y) const {
  assert(x >= 0 && x < width && y >= 0 && y < height);
  return rgba.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                        static_cast<std::size_t>(x)) *
                           4;
}

void flipRows(Image& image) {
  const std::size_t row = static_cast<std::size_t>(image.width) * 4;
  std::vector<std::uint8_t> tmp(row);
  for (int y = 0; y < image.height / 2; ++y) {
    std::uint8_t* a = image.rgba.data() + static_cast<std::size_t>(y) * row;
    std::uint8_t* b = image.rgba.data() + static_cast<std::size_t>(image.height - 1 - y) * row;
    std::memcpy(tmp.data(), a, row);
    std::memcpy(a, b, row);
    std::memcpy(b, tmp.data(), row);
  }
}

namespace {

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

Status writePng(const Image& image, const std::string& path, PngSpeed speed) {
  const std::size_t expected =
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 4;
  if (image.width <= 0 || image.height <= 0 || image.rgba.size() != expected) {
    return fail(
        "writing PNG {}: image is empty or its pixel array ({} bytes) does not match "
        "{}x{} RGBA",
        path, image.rgba.size(), image.width, image.height);
  }
  // Encode into memory, then write through the atomic file writer.
  stbi_write_png_compression_level = speed == PngSpeed::kFastest ? 1 : 8;
  std::vector<std::uint8_t> png;
  png.reserve(expected / 4);
  const int ok = stbi_write_png_to_func(appendBytes, &png, image.width, image.height, 4,
                                        image.rgba.data(), image.width * 4);
  if (ok == 0 || png.empty()) return fail("writing PNG {}: the encoder failed", path);
  return writeFileBytes(path, png);
}

}  // namespace vistel
