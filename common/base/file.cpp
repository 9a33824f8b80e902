#include "common/base/file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace vistel {
namespace {

template <typename Container>
Result<Container> readWhole(const std::string& path, std::size_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return fail("{}: is a directory, not a file", path);
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("{}: cannot open: {}", path, std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) return fail("{}: cannot determine size", path);
  if (static_cast<std::uint64_t>(size) > max_bytes) {
    return fail("{}: {} bytes is larger than the limit of {} bytes", path, size, max_bytes);
  }
  in.seekg(0, std::ios::beg);
  Container data(static_cast<std::size_t>(size), {});
  if (size > 0 && !in.read(reinterpret_cast<char*>(data.data()), size)) {
    return fail("{}: read failed after {} of {} bytes", path, in.gcount(), size);
  }
  return data;
}

Status writeWhole(const std::string& path, const void* data, std::size_t size) {
  const std::string tmp = path + ".part";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) return fail("{}: cannot create: {}", tmp, std::strerror(errno));
  const bool wrote = size == 0 || std::fwrite(data, 1, size, f) == size;
  const bool closed = std::fclose(f) == 0;
  if (!wrote || !closed) {
    std::remove(tmp.c_str());
    return fail("{}: write failed: {}", path, std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    return fail("{}: cannot rename into place: {}", path, ec.message());
  }
  return {};
}

}  // namespace

Result<std::vector<std::uint8_t>> readFileBytes(const std::string& path, std::size_t max_bytes) {
  return readWhole<std::vector<std::uint8_t>>(path, max_bytes);
}

Result<std::string> readFileText(const std::string& path, std::size_t max_bytes) {
  return readWhole<std::string>(path, max_bytes);
}

Status writeFileBytes(const std::string& path, std::span<const std::uint8_t> bytes) {
  return writeWhole(path, bytes.data(), bytes.size());
}

Status writeFileText(const std::string& path, std::string_view text) {
  return writeWhole(path, text.data(), text.size());
}

}  // namespace vistel
