#include "common/avatar/avatar_model.hpp"

namespace vistel {

Status validateAvatar(const AvatarModel& avatar) {
  if (Status s = validateSkeleton(avatar.skeleton); !s) return withContext("skeleton", s.error());
  if (Status s = validateSkinMesh(avatar.skin, avatar.skeleton.jointCount()); !s) {
    return withContext("skin", s.error());
  }
  return {};
}

}  // namespace vistel
