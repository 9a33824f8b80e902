// GlbBuilder: the binary chunk of a .glb being written and the JSON arrays that describe
// it (bufferViews, accessors). Every view starts 4-byte aligned; float accessors can carry
// the exact per-component min/max the validator checks. The caller puts views() and
// accessors() into its document, with one buffer of bin().size() bytes, and hands the
// JSON text and bin() to assembleGlb (glb_container.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/glb/gltf_enums.hpp"

namespace vistel {

class GlbBuilder {
 public:
  // Appends raw bytes as a new buffer view (`target` 0: none); returns the view's index.
  int addView(const void* data, std::size_t size, int target);

  // A float accessor of `components` per element ("SCALAR", "VEC3", "VEC4", "MAT4") over a
  // new view, with exact min/max when `bounds`; returns the accessor's index.
  int addFloats(std::span<const float> values, int components, const char* type, int target,
                bool bounds);

  // An integer accessor over a new view: `values` of component type `component_type`
  // (kGltfUnsignedByte, kGltfUnsignedShort, kGltfUnsignedInt), `per` to an element.
  template <typename T>
  int addIntegers(std::span<const T> values, int component_type, const char* type, int per,
                  int target) {
    return addAccessor({{"bufferView", addView(values.data(), values.size_bytes(), target)},
                        {"componentType", component_type},
                        {"count", values.size() / static_cast<std::size_t>(per)},
                        {"type", type}});
  }

  template <typename T>
  int addIntegers(const std::vector<T>& values, int component_type, const char* type, int per,
                  int target) {
    return addIntegers(std::span<const T>(values), component_type, type, per, target);
  }

  int addAccessor(nlohmann::json accessor);

  std::vector<std::uint8_t>& bin() { return bin_; }
  nlohmann::json& views() { return views_; }
  nlohmann::json& accessors() { return accessors_; }

 private:
  std::vector<std::uint8_t> bin_;
  nlohmann::json views_ = nlohmann::json::array();
  nlohmann::json accessors_ = nlohmann::json::array();
};

}  // namespace vistel
