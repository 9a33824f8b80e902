// A bounded byte queue for stream decoders: feed() appends arbitrary chunks, the decoder
// looks at the front and consumes what it used. Storage is reserved once; the queue never
// holds more than `capacity` bytes (when a feed would overflow it, the oldest bytes are
// dropped and counted, since a decoder that has not found a record in `capacity` bytes is
// looking at garbage). Allocation-free after construction.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace vistel {

class ByteStream {
 public:
  explicit ByteStream(std::size_t capacity = 4096) : capacity_(capacity) {
    data_.resize(2 * capacity);
  }

  void feed(std::span<const std::uint8_t> bytes) {
    if (bytes.size() > capacity_) {  // only the newest capacity_ bytes can matter
      dropped_ += size() + bytes.size() - capacity_;
      clear();
      bytes = bytes.subspan(bytes.size() - capacity_);
    }
    if (size() + bytes.size() > capacity_) {
      const std::size_t drop = size() + bytes.size() - capacity_;
      dropped_ += drop;
      head_ += drop;
    }
    if (tail_ + bytes.size() > data_.size()) compact();
    std::memcpy(data_.data() + tail_, bytes.data(), bytes.size());
    tail_ += bytes.size();
  }

  std::span<const std::uint8_t> front() const { return {data_.data() + head_, size()}; }
  std::size_t size() const { return tail_ - head_; }
  void consume(std::size_t n) {
    head_ += std::min(n, size());
    if (head_ == tail_) head_ = tail_ = 0;
  }
  void clear() { head_ = tail_ = 0; }
  // Bytes lost to overflow since construction.
  std::uint64_t dropped() const { return dropped_; }

 private:
  void compact() {
    const std::size_t n = size();
    std::memmove(data_.data(), data_.data() + head_, n);
    head_ = 0;
    tail_ = n;
  }

  std::vector<std::uint8_t> data_;  // 2 * capacity_ bytes of storage
  std::size_t capacity_;
  std::size_t head_ = 0;
  std::size_t tail_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace vistel
