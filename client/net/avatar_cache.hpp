// Avatars by content hash on the client side (DESIGN.md §6): decoded models in memory,
// and optionally their files in a folder on disk (<folder>/<hash>.vavatar), so a later
// session need not fetch them again. Every file is checked on the way in, from the
// network or from disk: its SHA-256 must be its name, and it must decode.
//
// Thread-safe (the network thread inserts, the render thread looks up).
#pragma once

#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <unordered_map>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel::net {

class AvatarCache {
 public:
  // disk_folder empty: memory only. The folder is created on first write.
  explicit AvatarCache(std::string disk_folder = "");

  // The model with this hash: from memory, else from the disk folder (checked); null if
  // neither has it (a bad disk file is ignored, logged and overwritten later).
  std::shared_ptr<const AvatarModel> find(const std::string& hash);
  // Checks bytes against the hash, decodes, keeps the model, and writes the file to the
  // disk folder. The error says what was wrong (the file is then not kept).
  Result<std::shared_ptr<const AvatarModel>> insert(const std::string& hash,
                                                    std::span<const std::uint8_t> bytes);

  const std::string& diskFolder() const { return disk_folder_; }

 private:
  std::string disk_folder_;
  std::mutex mutex_;
  std::unordered_map<std::string, std::shared_ptr<const AvatarModel>> models_;
};

}  // namespace vistel::net
