// FastrakParser: a pure byte-stream decoder for FASTRAK-class data records. Feed it the
// bytes exactly as they arrive (any chunking: single bytes, split records, many records at
// once); next() returns complete records in order. After garbage (line noise, a status
// reply, a lost byte) it resynchronises by scanning for a header ('0', station '1'..'4',
// status ' ' or a letter) whose record decodes plausibly (decodeFastrakRecord), so one bad
// byte costs at most the record it hit. Never throws or aborts on input; allocates nothing
// after construction.
#pragma once

#include <cstdint>
#include <span>

#include "common/sensors/byte_stream.hpp"
#include "common/sensors/fastrak_protocol.hpp"

namespace vistel {

class FastrakParser {
 public:
  // The format must pass validateFastrakFormat (asserted).
  explicit FastrakParser(FastrakFormat format);

  void feed(std::span<const std::uint8_t> bytes) { stream_.feed(bytes); }
  // Decodes the next complete record into `out`; false when more bytes are needed.
  bool next(FastrakRecord& out);
  // Forgets buffered bytes (after a mode change).
  void reset() { stream_.clear(); }

  const FastrakFormat& format() const { return format_; }
  std::size_t recordSize() const { return record_size_; }
  std::size_t buffered() const { return stream_.size(); }
  std::uint64_t recordCount() const { return records_; }
  // Bytes skipped while resynchronising (garbage, broken records, overflow).
  std::uint64_t discardedBytes() const { return discarded_ + stream_.dropped(); }

 private:
  FastrakFormat format_;
  std::size_t record_size_;
  ByteStream stream_;
  std::uint64_t records_ = 0;
  std::uint64_t discarded_ = 0;
};

}  // namespace vistel
