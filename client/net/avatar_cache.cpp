#include "client/net/avatar_cache.hpp"

#include <filesystem>

#include <spdlog/spdlog.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"

namespace vistel::net {

AvatarCache::AvatarCache(std::string disk_folder) : disk_folder_(std::move(disk_folder)) {}

std::shared_ptr<const AvatarModel> AvatarCache::find(const std::string& hash) {
  {
    std::lock_guard lock(mutex_);
    auto it = models_.find(hash);
    if (it != models_.end()) return it->second;
  }
  if (disk_folder_.empty()) return nullptr;

  // From disk: the file must hash to its name and decode.
  const std::string path = (std::filesystem::path(disk_folder_) / (hash + ".vavatar")).string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return nullptr;
  auto bytes = readFileBytes(path, 1u << 30);
  if (!bytes) return nullptr;
  if (avatarContentHash(*bytes) != hash) {
    spdlog::warn("avatar cache: {} does not hash to its name; ignoring it", path);
    return nullptr;
  }
  auto model = decodeAvatar(*bytes, path);
  if (!model) {
    spdlog::warn("avatar cache: {}", model.error().message);
    return nullptr;
  }
  auto shared = std::make_shared<const AvatarModel>(std::move(*model));
  std::lock_guard lock(mutex_);
  return models_.emplace(hash, shared).first->second;
}

Result<std::shared_ptr<const AvatarModel>> AvatarCache::insert(
    const std::string& hash, std::span<const std::uint8_t> bytes) {
  const std::string actual = avatarContentHash(bytes);
  if (actual != hash) return fail("avatar {}: the received file hashes to {}", hash, actual);
  auto model = decodeAvatar(bytes, "avatar " + hash.substr(0, 12));
  if (!model) return model.error();
  auto shared = std::make_shared<const AvatarModel>(std::move(*model));
  {
    std::lock_guard lock(mutex_);
    models_[hash] = shared;
  }
  if (!disk_folder_.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(disk_folder_, ec);
    const auto path = std::filesystem::path(disk_folder_) / (hash + ".vavatar");
    if (Status st = writeFileBytes(path.string(), bytes); !st) {
      spdlog::warn("avatar cache: {}", st.error().message);
    }
  }
  return shared;
}

}  // namespace vistel::net
