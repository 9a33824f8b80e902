// Little-endian byte writing and range-checked reading, for file formats (avatars,
// recordings). Readers never trust their input: every read checks the remaining size
// and a failed read latches (later reads fail too), so a decoder can read a whole
// record and check ok() once.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vistel {

static_assert(std::endian::native == std::endian::little, "vistel assumes a little-endian host");

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}

  void u8(std::uint8_t v) { out_.push_back(v); }
  void u16(std::uint16_t v) { raw(&v, sizeof v); }
  void u32(std::uint32_t v) { raw(&v, sizeof v); }
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void i32(std::int32_t v) { raw(&v, sizeof v); }
  void f32(float v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  // A u32 length, then the bytes.
  void string(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    raw(s.data(), s.size());
  }
  void raw(const void* data, std::size_t size) {
    if (size == 0) return;
    const std::size_t at = out_.size();
    out_.resize(at + size);
    std::memcpy(out_.data() + at, data, size);
  }
  template <typename T>
  void array(std::span<const T> items) {  // raw elements, no length
    raw(items.data(), items.size_bytes());
  }
  std::size_t size() const { return out_.size(); }
  // Overwrites a u32 written earlier at `offset` (for sizes known only afterwards).
  void patchU32(std::size_t offset, std::uint32_t v) { std::memcpy(out_.data() + offset, &v, 4); }

 private:
  std::vector<std::uint8_t>& out_;
};

class ByteReader {
 public:
  explicit ByteReader(std::span<const std::uint8_t> in) : in_(in) {}

  bool ok() const { return ok_; }
  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return ok_ ? in_.size() - pos_ : 0; }

  std::uint8_t u8() { return read<std::uint8_t>(); }
  std::uint16_t u16() { return read<std::uint16_t>(); }
  std::uint32_t u32() { return read<std::uint32_t>(); }
  std::uint64_t u64() { return read<std::uint64_t>(); }
  std::int32_t i32() { return read<std::int32_t>(); }
  float f32() { return read<float>(); }
  double f64() { return read<double>(); }
  // A u32 length (at most max_size), then the bytes.
  std::string string(std::size_t max_size = 1u << 16) {
    const std::uint32_t n = u32();
    if (!ok_ || n > max_size || n > remaining()) return failed<std::string>();
    std::string s(reinterpret_cast<const char*>(in_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  bool raw(void* out, std::size_t size) {
    if (!ok_ || size > remaining()) {
      ok_ = false;
      return false;
    }
    if (size == 0) return true;  // out may be null (an empty vector's data())
    std::memcpy(out, in_.data() + pos_, size);
    pos_ += size;
    return true;
  }
  // Reads count elements into out (resized), refusing counts the input cannot hold.
  template <typename T>
  bool array(std::vector<T>& out, std::size_t count) {
    if (!ok_ || count > remaining() / sizeof(T)) {
      ok_ = false;
      return false;
    }
    out.resize(count);
    return raw(out.data(), count * sizeof(T));
  }
  std::span<const std::uint8_t> bytes(std::size_t size) {
    if (!ok_ || size > remaining()) return failed<std::span<const std::uint8_t>>();
    auto s = in_.subspan(pos_, size);
    pos_ += size;
    return s;
  }
  void skip(std::size_t size) { (void)bytes(size); }

 private:
  template <typename T>
  T read() {
    T v{};
    raw(&v, sizeof v);
    return v;
  }
  template <typename T>
  T failed() {
    ok_ = false;
    return T{};
  }

  std::span<const std::uint8_t> in_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

// CRC-32 (IEEE 802.3, reflected, as zlib's crc32), for per-record checksums.
std::uint32_t crc32(std::span<const std::uint8_t> data, std::uint32_t crc = 0);

}  // namespace vistel
