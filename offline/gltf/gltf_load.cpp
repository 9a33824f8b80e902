#include "offline/gltf/gltf_load.hpp"

#include <exception>
#include <filesystem>
#include <limits>

#include "common/base/file.hpp"
#include "common/glb/glb_container.hpp"

namespace vistel {
namespace {

// tinygltf's messages come as several lines; one line reads better in an Error.
std::string oneLine(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  std::string out;
  for (char c : text) {
    if (c == '\n') {
      out += "; ";
    } else if (c != '\r') {
      out += c;
    }
  }
  return out;
}

// Images stay encoded. Those from data URIs and external files are kept as their bytes
// (image->image, as_is; at most the external-file cap); those in buffer views are left
// for the caller to read, range-checked, from the buffer view (tinygltf hands this
// callback a pointer it has not checked against the buffer's size).
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                    const unsigned char* bytes, int size, void* user) {
  const std::size_t max_bytes = *static_cast<const std::size_t*>(user);
  if (image == nullptr || image->bufferView >= 0 || bytes == nullptr || size <= 0) return true;
  if (static_cast<std::size_t>(size) > max_bytes) return true;
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

bool fileExists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

std::string expandPath(const std::string& path, void*) { return path; }

bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user) {
  const std::size_t max_bytes = *static_cast<const std::size_t*>(user);
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path, max_bytes);
  if (!bytes) {
    if (err != nullptr) *err = bytes.error().message;
    return false;
  }
  *out = std::move(*bytes);
  return true;
}

bool refuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err != nullptr) *err = "writing is disabled while importing";
  return false;
}

}  // namespace

Result<tinygltf::Model> loadGltfModel(std::span<const std::uint8_t> bytes, std::string_view source,
                                      const std::string& base_dir, std::size_t max_external_bytes,
                                      std::vector<std::string>& warnings) {
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
    return fail("{}: {} bytes is too large for a glTF file", source, bytes.size());
  }
  const bool glb = looksLikeGlb(bytes);
  if (glb) {
    if (Result<GlbChunks> chunks = parseGlbContainer(bytes, source); !chunks) return chunks.error();
  } else {
    // JSON: the first non-blank character (after an optional UTF-8 BOM) must be '{'.
    std::size_t i = 0;
    if (bytes.size() >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF) i = 3;
    while (i < bytes.size() &&
           (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\n' || bytes[i] == '\r')) {
      ++i;
    }
    if (i >= bytes.size() || bytes[i] != '{') {
      return fail("{}: not a glTF file (no GLB magic and no JSON object)", source);
    }
  }

  tinygltf::TinyGLTF loader;
  std::size_t cap = max_external_bytes;
  loader.SetImageLoader(&keepImageBytes, &cap);
  loader.SetFsCallbacks(
      tinygltf::FsCallbacks{&fileExists, &expandPath, &readWholeFile, &refuseWrite, &cap});
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    const auto size = static_cast<unsigned int>(bytes.size());
    if (glb) {
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size, base_dir);
    } else {
      ok = loader.LoadASCIIFromString(&model, &err, &warn,
                                      reinterpret_cast<const char*>(bytes.data()), size, base_dir);
    }
  } catch (const std::exception& e) {
    return fail("{}: glTF parser failed: {}", source, e.what());
  }
  if (!warn.empty()) warnings.push_back(fmt::format("{}: {}", source, oneLine(warn)));
  if (!ok) {
    return fail("{}: {}", source, err.empty() ? std::string("invalid glTF") : oneLine(err));
  }
  if (model.asset.version.empty() || model.asset.version[0] != '2') {
    return fail("{}: asset version '{}' (only glTF 2.x is supported)", source, model.asset.version);
  }
  return model;
}

}  // namespace vistel
