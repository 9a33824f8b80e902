#include "common/glb/glb_builder.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

namespace vistel {

int GlbBuilder::addView(const void* data, std::size_t size, int target) {
  while (bin_.size() % 4 != 0) bin_.push_back(0);
  const std::size_t offset = bin_.size();
  bin_.resize(offset + size);
  if (size > 0) std::memcpy(bin_.data() + offset, data, size);
  nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
  if (target != 0) view["target"] = target;
  views_.push_back(std::move(view));
  return static_cast<int>(views_.size()) - 1;
}

int GlbBuilder::addFloats(std::span<const float> values, int components, const char* type,
                          int target, bool bounds) {
  const auto k = static_cast<std::size_t>(components);
  nlohmann::json acc = {{"bufferView", addView(values.data(), values.size_bytes(), target)},
                        {"componentType", kGltfFloat},
                        {"count", values.size() / k},
                        {"type", type}};
  if (bounds) {
    std::vector<float> lo(k, std::numeric_limits<float>::max());
    std::vector<float> hi(k, std::numeric_limits<float>::lowest());
    for (std::size_t i = 0; i < values.size(); ++i) {
      lo[i % k] = std::min(lo[i % k], values[i]);
      hi[i % k] = std::max(hi[i % k], values[i]);
    }
    acc["min"] = lo;
    acc["max"] = hi;
  }
  return addAccessor(std::move(acc));
}

int GlbBuilder::addAccessor(nlohmann::json accessor) {
  accessors_.push_back(std::move(accessor));
  return static_cast<int>(accessors_.size()) - 1;
}

}  // namespace vistel
