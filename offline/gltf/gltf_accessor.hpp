// Range-checked decoding of glTF 2.0 accessors (tinygltf's Model holds them unchecked).
// Every index, offset, stride, count and component type is checked against the file
// before a byte is read, so a malformed file gives an Error, never a crash.
#pragma once

#include <initializer_list>
#include <string_view>
#include <vector>

#include <tiny_gltf.h>

#include "common/base/result.hpp"
#include "common/glb/gltf_enums.hpp"

namespace vistel {

struct AccessorData {
  int count = 0;       // elements
  int components = 0;  // per element (1 SCALAR .. 16 MAT4)
  int component_type = 0;
  bool normalized = false;
  std::vector<double> values;  // count * components; normalized integers mapped to [0,1] or
                               // [-1,1] as the spec says, other integers as they are
};

// What a use of an accessor requires: its element type ("SCALAR", "VEC3", ...) and the
// component types allowed (normalized integer types listed as negative values, e.g.
// -kGltfUnsignedByte for a normalized unsigned byte).
struct AccessorRule {
  std::string_view type;
  std::initializer_list<int> component_types;
};

// Decodes accessor `index` of `model` (dense data, optional sparse substitution). The
// error starts with "<source>: accessor <index>: ..." and says what is wrong (count beyond
// the buffer view, bad stride, unknown component type, non-finite float, ...).
// Cost: O(count * components); allocates the output.
Result<AccessorData> readAccessor(const tinygltf::Model& model, int index, std::string_view source,
                                  const AccessorRule& rule);

// "SCALAR", "VEC3", ... for a tinygltf type code ("?" when unknown).
std::string_view accessorTypeName(int type);

}  // namespace vistel
