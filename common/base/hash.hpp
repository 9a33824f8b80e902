// Non-cryptographic 64-bit hashing (FNV-1a) for determinism checks: e.g. "replaying a
// recording gives the same hash of deformed vertices with 1 or N threads".
#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>

namespace vistel {

inline constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;

inline std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = kFnvOffset) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

// Hashes the object representation of trivially copyable elements (floats by bits).
template <typename T>
std::uint64_t hashSpan(std::span<const T> items, std::uint64_t hash = kFnvOffset) {
  static_assert(std::is_trivially_copyable_v<T>);
  return fnv1a64(items.data(), items.size_bytes(), hash);
}

}  // namespace vistel
