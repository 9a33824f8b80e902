// Parsing a glTF 2.0 file (GLB or JSON) into a tinygltf::Model, safely: the GLB container
// is checked first, images are not decoded, external files are read only through
// vistel's file functions (size-capped), and nothing tinygltf throws escapes.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <tiny_gltf.h>

#include "common/base/result.hpp"

namespace vistel {

// Parses `bytes` (a .glb, or .gltf JSON text) named `source` in messages; external
// buffers are looked up in base_dir and may be at most max_external_bytes each.
// tinygltf's warnings are appended to `warnings`. The model's buffers, views and
// accessors are NOT checked beyond tinygltf's own checks: read them through
// readAccessor(). The error names the source and the reason.
Result<tinygltf::Model> loadGltfModel(std::span<const std::uint8_t> bytes, std::string_view source,
                                      const std::string& base_dir, std::size_t max_external_bytes,
                                      std::vector<std::string>& warnings);

}  // namespace vistel
