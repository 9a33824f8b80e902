#include "server/core/avatar_store.hpp"

#include "common/avatar/avatar_io.hpp"
#include "common/wire/posture_codec.hpp"

namespace vistel::server {

bool isContentHash(std::string_view hash) {
  if (hash.size() != 64) return false;
  for (char c : hash) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

const StoredAvatar* AvatarStore::find(std::string_view hash) const {
  auto it = entries_.find(std::string(hash));
  return it == entries_.end() ? nullptr : &it->second;
}

Status AvatarStore::add(std::string_view hash, std::vector<std::uint8_t> bytes,
                        std::string_view source) {
  // The bytes must be what was offered, and a valid avatar the wire can carry.
  const std::string actual = avatarContentHash(bytes);
  if (actual != hash) {
    return fail("{}: content hash {} does not match the offered {}", source, actual, hash);
  }
  auto model = decodeAvatar(bytes, source);
  if (!model) return model.error();
  const int joints = model->skeleton.jointCount();
  if (joints < 1 || joints > wire::kMaxWireJoints) {
    return fail("{}: {} joints (the posture stream carries 1..{})", source, joints,
                wire::kMaxWireJoints);
  }
  if (entries_.count(std::string(hash))) return {};

  // Keep the file (for fetches) and the collision model; the skin is not needed here.
  auto collision = makeCollisionModel(std::move(*model), limits_, source);
  if (!collision) return collision.error();
  StoredAvatar entry;
  entry.joint_count = joints;
  entry.collision = std::move(*collision);
  entry.bytes = std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes));
  entries_.emplace(std::string(hash), std::move(entry));
  return {};
}

void AvatarStore::addRef(std::string_view hash) {
  auto it = entries_.find(std::string(hash));
  if (it != entries_.end()) ++it->second.refs;
}

void AvatarStore::release(std::string_view hash) {
  auto it = entries_.find(std::string(hash));
  if (it != entries_.end() && --it->second.refs <= 0) entries_.erase(it);
}

void AvatarStore::pruneUnreferenced() {
  std::erase_if(entries_, [](const auto& kv) { return kv.second.refs <= 0; });
}

}  // namespace vistel::server
