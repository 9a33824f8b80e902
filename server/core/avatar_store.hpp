// The server's avatars, by content hash (DESIGN.md §6: avatars travel by hash). An entry
// exists while at least one member uses it: the file's bytes (served to members that
// fetch it) and its collision model (skeleton, primitives, combination graph: what the
// rooms' collision worlds pose). Uploads are validated before they enter: complete,
// hashing to the offered hash, decoding to a valid AvatarModel with at most 255 joints,
// and an implicit model (if any) within the server's CollisionLimits.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "common/base/result.hpp"
#include "server/core/collision_model.hpp"

namespace vistel::server {

struct StoredAvatar {
  std::shared_ptr<const std::vector<std::uint8_t>> bytes;  // the .vavatar file
  std::shared_ptr<const CollisionModel> collision;
  int joint_count = 0;
  int refs = 0;  // members using it
};

class AvatarStore {
 public:
  explicit AvatarStore(const CollisionLimits& limits = {}) : limits_(limits) {}

  const StoredAvatar* find(std::string_view hash) const;

  // Validates an uploaded file against its offered hash; on success stores it (refs 0)
  // unless present. The error says why the upload is refused.
  Status add(std::string_view hash, std::vector<std::uint8_t> bytes, std::string_view source);

  void addRef(std::string_view hash);
  // Drops a reference; the entry is erased when none remain.
  void release(std::string_view hash);

  // Erases entries no member uses (e.g. an upload whose uploader left meanwhile).
  void pruneUnreferenced();

  std::size_t size() const { return entries_.size(); }

 private:
  CollisionLimits limits_;
  std::unordered_map<std::string, StoredAvatar> entries_;
};

// True for 64 lowercase hex characters (the form of avatarContentHash).
bool isContentHash(std::string_view hash);

}  // namespace vistel::server
