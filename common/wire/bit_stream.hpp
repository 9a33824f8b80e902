// Bit streams for the UDP codec (proto/WIRE.md §3): one serialize function per message,
// written once as a template over the stream, reads, writes and measures the same bits,
// so the three cannot drift.
//
// Bit order: little-endian throughout. A field of n bits is written least significant
// bit first; stream bit i is bit (i % 8) of byte i / 8. A byte-aligned 16/32/64-bit field
// is therefore exactly its little-endian bytes.
//
// Every serialize call returns bool. WriteStream and MeasureStream always succeed (the
// caller passes values that fit: asserted). ReadStream fails, and stays failed, when a
// read would pass the end of the input: packet data comes from the network and may be
// malicious, so readers never assume a size.
#pragma once

#include <algorithm>
#include <bit>
#include <cassert>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace vistel::wire {

class WriteStream {
 public:
  static constexpr bool kReading = false;

  // Appends to `out` (not cleared).
  explicit WriteStream(std::vector<std::uint8_t>& out) : out_(out), start_(out.size()) {}

  // Writes the low `bits` bits of value (1..32).
  bool bits(std::uint32_t& value, int bits) {
    assert(bits >= 1 && bits <= 32);
    assert(bits == 32 || (value >> bits) == 0);
    scratch_ |= static_cast<std::uint64_t>(value) << scratch_bits_;
    scratch_bits_ += bits;
    while (scratch_bits_ >= 8) {
      out_.push_back(static_cast<std::uint8_t>(scratch_ & 0xFFu));
      scratch_ >>= 8;
      scratch_bits_ -= 8;
    }
    return true;
  }
  // Pads with zero bits to the next byte boundary.
  bool align() {
    if (scratch_bits_ > 0) {
      out_.push_back(static_cast<std::uint8_t>(scratch_ & 0xFFu));
      scratch_ = 0;
      scratch_bits_ = 0;
    }
    return true;
  }
  bool ok() const { return true; }
  // Whole bytes written so far by this stream (call after align()).
  std::size_t bytesWritten() const { return out_.size() - start_; }

 private:
  std::vector<std::uint8_t>& out_;
  std::size_t start_;
  std::uint64_t scratch_ = 0;
  int scratch_bits_ = 0;
};

class ReadStream {
 public:
  static constexpr bool kReading = true;

  explicit ReadStream(std::span<const std::uint8_t> in) : in_(in) {}

  // Reads `bits` bits (1..32) into value; false (and latched) past the end.
  bool bits(std::uint32_t& value, int bits) {
    assert(bits >= 1 && bits <= 32);
    if (!ok_ || static_cast<std::size_t>(bits) > bitsLeft()) {
      ok_ = false;
      value = 0;
      return false;
    }
    std::uint64_t v = 0;
    int got = 0;
    while (got < bits) {
      const std::size_t byte = bit_pos_ / 8;
      const int in_byte = static_cast<int>(bit_pos_ % 8);
      const int take = std::min(8 - in_byte, bits - got);
      const std::uint64_t chunk = (in_[byte] >> in_byte) & ((1u << take) - 1u);
      v |= chunk << got;
      got += take;
      bit_pos_ += static_cast<std::size_t>(take);
    }
    value = static_cast<std::uint32_t>(v);
    return true;
  }
  // Skips to the next byte boundary; the skipped bits must be zero (else fails).
  bool align() {
    const int rest = static_cast<int>((8 - bit_pos_ % 8) % 8);
    if (rest == 0) return ok_;
    std::uint32_t pad = 0;
    if (!bits(pad, rest)) return false;
    if (pad != 0) ok_ = false;
    return ok_;
  }
  bool ok() const { return ok_; }
  std::size_t bitsLeft() const { return in_.size() * 8 - bit_pos_; }
  // True when every input byte has been consumed (a message must fill its packet).
  bool atEnd() const { return ok_ && bit_pos_ == in_.size() * 8; }
  std::size_t bytesRead() const { return (bit_pos_ + 7) / 8; }

 private:
  std::span<const std::uint8_t> in_;
  std::size_t bit_pos_ = 0;
  bool ok_ = true;
};

class MeasureStream {
 public:
  static constexpr bool kReading = false;

  bool bits(std::uint32_t& /*value*/, int bits) {
    bits_ += static_cast<std::size_t>(bits);
    return true;
  }
  bool align() {
    bits_ = (bits_ + 7) / 8 * 8;
    return true;
  }
  bool ok() const { return true; }
  std::size_t bitCount() const { return bits_; }
  std::size_t byteCount() const { return (bits_ + 7) / 8; }

 private:
  std::size_t bits_ = 0;
};

// ----- field helpers (the same call reads, writes or measures) -----

template <typename Stream>
bool serializeU8(Stream& s, std::uint8_t& v) {
  std::uint32_t x = v;
  if (!s.bits(x, 8)) return false;
  v = static_cast<std::uint8_t>(x);
  return true;
}

template <typename Stream>
bool serializeU16(Stream& s, std::uint16_t& v) {
  std::uint32_t x = v;
  if (!s.bits(x, 16)) return false;
  v = static_cast<std::uint16_t>(x);
  return true;
}

template <typename Stream>
bool serializeI16(Stream& s, std::int16_t& v) {
  std::uint32_t x = static_cast<std::uint16_t>(v);
  if (!s.bits(x, 16)) return false;
  v = static_cast<std::int16_t>(static_cast<std::uint16_t>(x));
  return true;
}

template <typename Stream>
bool serializeU32(Stream& s, std::uint32_t& v) {
  return s.bits(v, 32);
}

template <typename Stream>
bool serializeU64(Stream& s, std::uint64_t& v) {
  std::uint32_t lo = static_cast<std::uint32_t>(v);
  std::uint32_t hi = static_cast<std::uint32_t>(v >> 32);
  if (!s.bits(lo, 32) || !s.bits(hi, 32)) return false;
  v = (static_cast<std::uint64_t>(hi) << 32) | lo;
  return true;
}

// IEEE-754 binary64, little-endian. Readers must still check the value is finite.
template <typename Stream>
bool serializeF64(Stream& s, double& v) {
  std::uint64_t x = std::bit_cast<std::uint64_t>(v);
  if (!serializeU64(s, x)) return false;
  v = std::bit_cast<double>(x);
  return true;
}

// An n-bit unsigned field (1..32) whose value must be <= max (checked when reading).
template <typename Stream>
bool serializeBounded(Stream& s, std::uint32_t& v, int bits, std::uint32_t max) {
  if (!s.bits(v, bits)) return false;
  return !Stream::kReading || v <= max;
}

}  // namespace vistel::wire
