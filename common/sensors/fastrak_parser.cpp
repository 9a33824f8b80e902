#include "common/sensors/fastrak_parser.hpp"

#include <cassert>
#include <utility>

namespace vistel {

FastrakParser::FastrakParser(FastrakFormat format)
    : format_(std::move(format)),
      record_size_(fastrakRecordSize(format_)),
      stream_(std::max<std::size_t>(4096, 8 * record_size_)) {
  assert(validateFastrakFormat(format_).ok());
}

bool FastrakParser::next(FastrakRecord& out) {
  for (;;) {
    const std::span<const std::uint8_t> bytes = stream_.front();
    // Skip to the next byte that can start a record header.
    std::size_t skip = 0;
    while (skip < bytes.size() && bytes[skip] != '0') ++skip;
    if (skip > 0) {
      discarded_ += skip;
      stream_.consume(skip);
      continue;
    }
    if (bytes.size() < record_size_) return false;  // wait for the rest
    if (decodeFastrakRecord(bytes.first(record_size_), format_, out)) {
      stream_.consume(record_size_);
      ++records_;
      return true;
    }
    // Not a record here: this '0' was garbage; look from the next byte.
    ++discarded_;
    stream_.consume(1);
  }
}

}  // namespace vistel
