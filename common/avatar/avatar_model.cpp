#include "common/avatar/avatar_model.hpp"

namespace vistel {

Status validateAvatar(const AvatarModel& avatar) {
  if (Status s = validateSkeleton(avatar.skeleton); !s) return withContext("skeleton", s.error());
  if (Status s = validateSkinMesh(avatar.skin, avatar.skeleton.jointCount()); !s) {
    return withContext("skin", s.error());
  }
  if (Status s =
          validateLook(avatar.look, avatar.skin.positions.size(), avatar.skin.indices.size());
      !s) {
    return withContext("look", s.error());
  }
  if (avatar.implicit) {
    if (Status s = validateImplicitModel(*avatar.implicit, avatar.skeleton.jointCount(),
                                         avatar.skin.vertexCount());
        !s) {
      return withContext("implicit model", s.error());
    }
  }
  return {};
}

}  // namespace vistel
