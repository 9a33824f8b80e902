#include "offline/gltf/gltf_accessor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace vistel {
namespace {

// Decoded values per accessor at most (8 bytes each): 1 GiB of doubles.
constexpr std::size_t kMaxAccessorValues = std::size_t{1} << 27;

int componentSize(int component_type) {
  switch (component_type) {
    case kGltfByte:
    case kGltfUnsignedByte:
      return 1;
    case kGltfShort:
    case kGltfUnsignedShort:
      return 2;
    case kGltfUnsignedInt:
    case kGltfFloat:
      return 4;
    default:
      return 0;
  }
}

int componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
      return 4;
    case TINYGLTF_TYPE_MAT2:
      return 4;
    case TINYGLTF_TYPE_MAT3:
      return 9;
    case TINYGLTF_TYPE_MAT4:
      return 16;
    default:
      return 0;
  }
}

std::string_view componentName(int component_type) {
  switch (component_type) {
    case kGltfByte:
      return "byte";
    case kGltfUnsignedByte:
      return "unsigned byte";
    case kGltfShort:
      return "short";
    case kGltfUnsignedShort:
      return "unsigned short";
    case kGltfUnsignedInt:
      return "unsigned int";
    case kGltfFloat:
      return "float";
    default:
      return "unknown";
  }
}

// One component at p (little-endian host), normalised when asked.
double decodeComponent(const std::uint8_t* p, int component_type, bool normalized) {
  switch (component_type) {
    case kGltfByte: {
      std::int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case kGltfUnsignedByte: {
      std::uint8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? v / 255.0 : v;
    }
    case kGltfShort: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case kGltfUnsignedShort: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case kGltfUnsignedInt: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return normalized ? v / 4294967295.0 : v;
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

// A byte range [offset, offset + size) of a buffer view, checked against its buffer.
struct ViewBytes {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::size_t stride = 0;  // 0 = tightly packed
};

Result<ViewBytes> viewBytes(const tinygltf::Model& model, int view_index, std::string_view where) {
  if (view_index < 0 || static_cast<std::size_t>(view_index) >= model.bufferViews.size()) {
    return fail("{}: buffer view {} does not exist ({} buffer views)", where, view_index,
                model.bufferViews.size());
  }
  const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(view_index)];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
    return fail("{}: buffer view {} refers to buffer {} of {}", where, view_index, view.buffer,
                model.buffers.size());
  }
  const std::vector<unsigned char>& data =
      model.buffers[static_cast<std::size_t>(view.buffer)].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset) {
    return fail("{}: buffer view {} (offset {}, length {}) exceeds buffer {} ({} bytes)", where,
                view_index, view.byteOffset, view.byteLength, view.buffer, data.size());
  }
  if (view.byteStride != 0 &&
      (view.byteStride < 4 || view.byteStride > 252 || view.byteStride % 4 != 0)) {
    return fail("{}: buffer view {} has byte stride {} (must be 4..252, a multiple of 4)", where,
                view_index, view.byteStride);
  }
  return ViewBytes{data.data() + view.byteOffset, view.byteLength, view.byteStride};
}

// Checks that `count` elements of `element_size` bytes at `offset` with `stride` fit.
Status checkFits(std::size_t offset, std::size_t count, std::size_t element_size,
                 std::size_t stride, std::size_t view_size, std::string_view what,
                 std::string_view where) {
  if (count == 0) return {};
  if (offset > view_size) {
    return fail("{}: byte offset {} exceeds {} ({} bytes)", where, offset, what, view_size);
  }
  const std::size_t room = view_size - offset;
  if (element_size > room || (count - 1) > (room - element_size) / stride) {
    return fail("{}: count {} exceeds {} ({} bytes from offset {}, stride {})", where, count, what,
                view_size, offset, stride);
  }
  return {};
}

}  // namespace

std::string_view accessorTypeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    case TINYGLTF_TYPE_MAT2:
      return "MAT2";
    case TINYGLTF_TYPE_MAT3:
      return "MAT3";
    case TINYGLTF_TYPE_MAT4:
      return "MAT4";
    default:
      return "?";
  }
}

Result<AccessorData> readAccessor(const tinygltf::Model& model, int index, std::string_view source,
                                  const AccessorRule& rule) {
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
    return fail("{}: accessor {} does not exist ({} accessors)", source, index,
                model.accessors.size());
  }
  const std::string where = fmt::format("{}: accessor {}", source, index);
  const tinygltf::Accessor& acc = model.accessors[static_cast<std::size_t>(index)];

  // Element type, component type and normalisation against the rule.
  const int components = componentCount(acc.type);
  const int csize = componentSize(acc.componentType);
  if (components == 0) return fail("{}: unknown element type {}", where, acc.type);
  if (csize == 0) return fail("{}: unknown component type {}", where, acc.componentType);
  if (accessorTypeName(acc.type) != rule.type) {
    return fail("{}: element type {} where {} is required", where, accessorTypeName(acc.type),
                rule.type);
  }
  const int key = acc.normalized ? -acc.componentType : acc.componentType;
  if (std::find(rule.component_types.begin(), rule.component_types.end(), key) ==
      rule.component_types.end()) {
    return fail("{}: component type {}{} is not allowed here", where,
                acc.normalized ? "normalized " : "", componentName(acc.componentType));
  }
  if (components > 4 && csize != 4) {
    return fail("{}: matrices must have 4-byte components", where);
  }
  if (acc.count == 0) return fail("{}: count is 0", where);
  if (acc.count > kMaxAccessorValues / static_cast<std::size_t>(components)) {
    return fail("{}: count {} is too large (at most {} values per accessor)", where, acc.count,
                kMaxAccessorValues);
  }

  AccessorData out;
  out.count = static_cast<int>(acc.count);
  out.components = components;
  out.component_type = acc.componentType;
  out.normalized = acc.normalized;
  const std::size_t element_size =
      static_cast<std::size_t>(components) * static_cast<std::size_t>(csize);

  // Dense data (absent buffer view = zeros, as the spec says).
  if (acc.bufferView >= 0) {
    Result<ViewBytes> view = viewBytes(model, acc.bufferView, where);
    if (!view) return view.error();
    const std::size_t stride = view->stride != 0 ? view->stride : element_size;
    if (stride < element_size) {
      return fail("{}: byte stride {} is smaller than the element size {}", where, stride,
                  element_size);
    }
    const std::string what = fmt::format("buffer view {}", acc.bufferView);
    if (Status s =
            checkFits(acc.byteOffset, acc.count, element_size, stride, view->size, what, where);
        !s) {
      return s.error();
    }
    out.values.resize(acc.count * static_cast<std::size_t>(components));
    for (std::size_t e = 0; e < acc.count; ++e) {
      const std::uint8_t* p = view->data + acc.byteOffset + e * stride;
      for (int c = 0; c < components; ++c) {
        out.values[e * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)] =
            decodeComponent(p + c * csize, acc.componentType, acc.normalized);
      }
    }
  } else if (!acc.sparse.isSparse) {
    return fail("{}: has neither a buffer view nor sparse data", where);
  } else {
    out.values.assign(acc.count * static_cast<std::size_t>(components), 0.0);
  }

  // Sparse substitution: strictly increasing indices, then one value element each.
  if (acc.sparse.isSparse) {
    const auto& sp = acc.sparse;
    if (sp.count < 1 || static_cast<std::size_t>(sp.count) > acc.count) {
      return fail("{}: sparse count {} outside 1..{}", where, sp.count, acc.count);
    }
    const int isize = componentSize(sp.indices.componentType);
    if (sp.indices.componentType != kGltfUnsignedByte &&
        sp.indices.componentType != kGltfUnsignedShort &&
        sp.indices.componentType != kGltfUnsignedInt) {
      return fail("{}: sparse indices have component type {}", where, sp.indices.componentType);
    }
    Result<ViewBytes> iview = viewBytes(model, sp.indices.bufferView, where + " sparse indices");
    if (!iview) return iview.error();
    Result<ViewBytes> vview = viewBytes(model, sp.values.bufferView, where + " sparse values");
    if (!vview) return vview.error();
    const auto n = static_cast<std::size_t>(sp.count);
    if (sp.indices.byteOffset < 0 || sp.values.byteOffset < 0) {
      return fail("{}: negative sparse byte offset", where);
    }
    if (Status s = checkFits(static_cast<std::size_t>(sp.indices.byteOffset), n,
                             static_cast<std::size_t>(isize), static_cast<std::size_t>(isize),
                             iview->size, "the sparse indices' buffer view", where);
        !s) {
      return s.error();
    }
    if (Status s = checkFits(static_cast<std::size_t>(sp.values.byteOffset), n, element_size,
                             element_size, vview->size, "the sparse values' buffer view", where);
        !s) {
      return s.error();
    }
    double previous = -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double target =
          decodeComponent(iview->data + static_cast<std::size_t>(sp.indices.byteOffset) +
                              i * static_cast<std::size_t>(isize),
                          sp.indices.componentType, false);
      if (target <= previous || target >= static_cast<double>(acc.count)) {
        return fail("{}: sparse index {} at position {} is out of range or not increasing", where,
                    target, i);
      }
      previous = target;
      const std::uint8_t* p =
          vview->data + static_cast<std::size_t>(sp.values.byteOffset) + i * element_size;
      const auto row = static_cast<std::size_t>(target) * static_cast<std::size_t>(components);
      for (int c = 0; c < components; ++c) {
        out.values[row + static_cast<std::size_t>(c)] =
            decodeComponent(p + c * csize, acc.componentType, acc.normalized);
      }
    }
  }

  // Floats must be finite.
  if (acc.componentType == kGltfFloat) {
    for (std::size_t i = 0; i < out.values.size(); ++i) {
      if (!std::isfinite(out.values[i])) {
        return fail("{}: element {} has a non-finite value", where,
                    i / static_cast<std::size_t>(components));
      }
    }
  }
  return out;
}

}  // namespace vistel
