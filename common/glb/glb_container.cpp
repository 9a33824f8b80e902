#include "common/glb/glb_container.hpp"

#include "common/base/bytes.hpp"

namespace vistel {

bool looksLikeGlb(std::span<const std::uint8_t> bytes) {
  ByteReader in(bytes);
  return in.u32() == kGlbMagic && in.ok();
}

Result<GlbChunks> parseGlbContainer(std::span<const std::uint8_t> bytes, std::string_view source) {
  // Header: magic, version, total length.
  if (bytes.size() < 12) {
    return fail("{}: {} bytes, shorter than the 12-byte GLB header", source, bytes.size());
  }
  ByteReader in(bytes);
  const std::uint32_t magic = in.u32();
  const std::uint32_t version = in.u32();
  const std::uint32_t length = in.u32();
  if (magic != kGlbMagic) return fail("{}: byte 0: not a GLB file (wrong magic)", source);
  if (version != 2)
    return fail("{}: byte 4: GLB version {} (only 2 is supported)", source, version);
  if (length != bytes.size()) {
    return fail("{}: byte 8: header says {} bytes but the file has {} (truncated or padded)",
                source, length, bytes.size());
  }

  // Chunks: JSON first, then an optional BIN; others are skipped.
  GlbChunks out;
  bool first = true;
  while (in.remaining() > 0) {
    const std::size_t at = in.offset();
    if (in.remaining() < 8) {
      return fail("{}: byte {}: {} bytes left, too few for a chunk header", source, at,
                  in.remaining());
    }
    const std::uint32_t chunk_length = in.u32();
    const std::uint32_t chunk_type = in.u32();
    if (chunk_length > in.remaining()) {
      return fail("{}: byte {}: chunk length {} exceeds the {} bytes left", source, at,
                  chunk_length, in.remaining());
    }
    const std::span<const std::uint8_t> payload = in.bytes(chunk_length);
    if (first) {
      if (chunk_type != kGlbChunkJson) {
        return fail("{}: byte {}: the first chunk is not JSON (type 0x{:08x})", source, at,
                    chunk_type);
      }
      if (chunk_length == 0) return fail("{}: byte {}: empty JSON chunk", source, at);
      out.json = payload;
      first = false;
    } else if (chunk_type == kGlbChunkBin && !out.has_bin) {
      out.bin = payload;
      out.has_bin = true;
    } else if (chunk_type == kGlbChunkJson) {
      return fail("{}: byte {}: a second JSON chunk", source, at);
    }
  }
  if (first) return fail("{}: byte 12: no JSON chunk", source);
  return out;
}

std::vector<std::uint8_t> assembleGlb(std::string_view json, std::span<const std::uint8_t> bin) {
  const std::size_t json_padded = (json.size() + 3) / 4 * 4;
  const std::size_t bin_padded = (bin.size() + 3) / 4 * 4;
  const std::size_t total = 12 + 8 + json_padded + (bin.empty() ? 0 : 8 + bin_padded);
  std::vector<std::uint8_t> bytes;
  bytes.reserve(total);
  ByteWriter out(bytes);
  out.u32(kGlbMagic);
  out.u32(2);
  out.u32(static_cast<std::uint32_t>(total));
  out.u32(static_cast<std::uint32_t>(json_padded));
  out.u32(kGlbChunkJson);
  out.raw(json.data(), json.size());
  for (std::size_t i = json.size(); i < json_padded; ++i) out.u8(' ');
  if (!bin.empty()) {
    out.u32(static_cast<std::uint32_t>(bin_padded));
    out.u32(kGlbChunkBin);
    out.raw(bin.data(), bin.size());
    for (std::size_t i = bin.size(); i < bin_padded; ++i) out.u8(0);
  }
  return bytes;
}

}  // namespace vistel
